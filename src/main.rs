//! `crosscheck`: run the verification cases through the engines and write the report (the
//! command line is [`crosscheck::cli`]).

fn main() -> std::process::ExitCode {
    crosscheck::cli::main_with(Vec::new())
}
