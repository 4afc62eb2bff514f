//! Progress on standard error while a run works: a bar (indicatif) where the `cli` feature is
//! on and standard error is a terminal; nothing otherwise (a library embedding crosscheck
//! without the command line draws none).

/// A progress bar, or nothing.
pub struct Progress {
    #[cfg(feature = "cli")]
    bar: indicatif::ProgressBar,
}

impl Progress {
    /// A bar for `len` tasks, shown only where `shown` and standard error is a terminal.
    pub fn new(len: usize, shown: bool) -> Progress {
        #[cfg(feature = "cli")]
        {
            use std::io::IsTerminal;
            let bar = if shown && std::io::stderr().is_terminal() {
                indicatif::ProgressBar::new(len as u64)
            } else {
                indicatif::ProgressBar::hidden()
            };
            bar.set_style(
                indicatif::ProgressStyle::with_template(
                    "[{elapsed_precise}] {bar:30} {pos}/{len} {msg}",
                )
                .expect("valid progress template")
                .progress_chars("=> "),
            );
            Progress { bar }
        }
        #[cfg(not(feature = "cli"))]
        {
            let _ = (len, shown);
            Progress {}
        }
    }

    /// `n` more tasks done.
    pub fn inc(&self, n: u64) {
        #[cfg(feature = "cli")]
        self.bar.inc(n);
        #[cfg(not(feature = "cli"))]
        let _ = n;
    }

    /// `n` more tasks to do.
    pub fn inc_length(&self, n: u64) {
        #[cfg(feature = "cli")]
        self.bar.inc_length(n);
        #[cfg(not(feature = "cli"))]
        let _ = n;
    }

    /// What is being done.
    pub fn set_message(&self, message: impl Into<std::borrow::Cow<'static, str>>) {
        #[cfg(feature = "cli")]
        self.bar.set_message(message);
        #[cfg(not(feature = "cli"))]
        let _ = message.into();
    }

    /// Done: the bar is cleared.
    pub fn finish_and_clear(&self) {
        #[cfg(feature = "cli")]
        self.bar.finish_and_clear();
    }
}
