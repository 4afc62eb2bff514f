//! What one increment costs, per seed case and engine, and what a run costs before its first
//! increment (the setup: compiling the scene, the stable increment, the static steps).
//!
//! `increment/<case>/<engine>`: a whole run at a tenth of the case's increment (rapier's matched
//! configuration takes the same, through the job planner; its default configuration keeps
//! 1/60 s), with criterion's throughput set to the increments the run takes, so the report's
//! "elem/s" is increments per second (ns per increment = 1e9 / that). The runs are 10^5 to
//! 2·10^5 increments long, so the setup (measured apart below, at most a few µs) is spread
//! over them; the 501 output rows are not spread as thin (`increment_long` below). `analytic`
//! is left out: it does not step in time.
//!
//! `increment_long/<case>/<engine>`: the same at a hundredth of the case's increment (10^6 to
//! 2·10^6 increments), `explicit` and `explicit_small` only. An output row costs far more than
//! an increment (the increment that writes it takes the general path, and the batch of
//! increments between rows starts and ends around it), so with ten times as many increments
//! between the same rows, the difference from `increment/…` is what the rows add there.
//!
//! `setup/<case>/explicit`: the explicit engine's stable-increment analysis, which compiles the
//! scene, runs its static steps and linearises it (what a run does before stepping).
//!
//! `floor/<case>/{registers,slices}`: the arithmetic floor (`run::floor`), the same recurrence
//! as the explicit engine's on the single damped oscillator of springs_grounded_a and
//! springs_grounded_b (`tests/floor.rs`: equal to round-off), written out by hand, at the same increment and length as `increment/<case>/…`:
//! with the state in registers (the dependent chain alone) and in heap slices, one pass per
//! stage (what a scene-driven engine must at least do). `floor/<case>/slices` of the pinned 2D
//! rigid cases: the least arithmetic of the same scheme on a body turning about a pin
//! (`run::floor::PinnedBody`), in heap slices; of rigid2d_slide_surface: the same on a body
//! sliding along x and turning with its mass centre off its reference node, whose centripetal
//! force reads the centred velocity, iterated with the engine's stop rule
//! (`run::floor::SlidingBody`), in heap slices; of rigid3d_slide_surface: the same body in 3D
//! with the arithmetic a 3D engine needs (a quaternion turned with compensated sums, body
//! points, forces, moments and the centripetal force as 3-vectors, the solve reduced to the
//! two free DOFs as the engine's body solve reduces it: `run::floor::TurningBody3d`), in heap
//! slices; of rigid2d_slide_lumped and rigid3d_slide_lumped: the same bodies with the mass
//! centre on the reference node, whose accelerations do not read the velocity and are formed
//! once per increment; of rigid3d_pin_lumped and rigid3d_pin_surface: the 3D body pinned at its
//! reference node (`run::floor::TurningBody3d`), whose accelerations do not read the velocity
//! either; of springs_grounded_c and springs_n2n_c: the same recurrence as the engine's on
//! masses pulled along a line by axial springs and the dashpot solved along its turning line
//! (`run::floor::AxialOscillator`, `tests/floor.rs`: equal to round-off), in heap slices; of
//! springs_n2n_b: the same recurrence on masses that move along one line, on springs and a
//! dashpot of fixed direction along it, in the one coordinate each mass has
//! (`run::floor::LineOscillator`, `tests/floor.rs`: equal to round-off), in heap slices.
//!
//! Run with `cargo bench --bench increment`; `BENCHMARKS.md` gives the table.
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use crosscheck::case;
use crosscheck::engines::RunSettings;
use crosscheck::engines::explicit::ExplicitEngine;
use crosscheck::run::floor::{self, DampedOscillator, REFINEMENT};
use crosscheck::run::matching;
use crosscheck::scene::IncrementRule;
use std::hint::black_box;
use std::time::Duration;

fn seed_cases() -> Vec<crosscheck::scene::Scene> {
    case::discover(&case::cases_dir())
        .expect("cases/")
        .iter()
        .map(|p| case::load(p).expect("a valid seed case"))
        .collect()
}

/// Whole runs of every seed case by the engines `chosen` at the case's increment divided by
/// `refinement` (the default configurations keep their own 1/60 s), in the group `name`, with
/// criterion's throughput set to the increments each run takes.
fn whole_runs(c: &mut Criterion, name: &str, refinement: f64, chosen: impl Fn(&str) -> bool) {
    let mut group = c.benchmark_group(name);
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(2));
    for scene in seed_cases() {
        for engine in crosscheck::run::registry::all() {
            if engine.name() == "analytic" || !chosen(engine.name()) {
                continue;
            }
            let finer = match scene.settings.increment {
                IncrementRule::Given(h) if !engine.name().ends_with("_default") => RunSettings {
                    increment: Some(IncrementRule::Given(h / refinement)),
                    ..RunSettings::default()
                },
                _ => RunSettings::default(),
            };
            let settings = matching::job_settings(engine.as_ref(), &scene, &finer);
            let steps = engine
                .run(&scene, &settings)
                .expect("a seed case runs")
                .info
                .steps;
            group.throughput(Throughput::Elements(steps));
            group.bench_function(format!("{}/{}", scene.id, engine.name()), |b| {
                b.iter(|| engine.run(black_box(&scene), &settings).expect("runs"))
            });
        }
    }
    group.finish();
}

/// A tenth of the case's increment (10^5 to 2·10^5 increments), so the setup is spread thin;
/// every engine.
fn increment(c: &mut Criterion) {
    whole_runs(c, "increment", REFINEMENT, |_| true);
}

/// A hundredth of the case's increment (10^6 to 2·10^6 increments), the explicit engines only:
/// ten times as many increments between the same 501 output rows, so the difference from
/// `increment/…` is what the rows cost.
fn increment_long(c: &mut Criterion) {
    whole_runs(c, "increment_long", 10.0 * REFINEMENT, |name| {
        name.starts_with("explicit")
    });
}

fn setup(c: &mut Criterion) {
    let mut group = c.benchmark_group("setup");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_millis(200))
        .measurement_time(Duration::from_secs(1));
    for scene in seed_cases() {
        for engine in [ExplicitEngine::finite(), ExplicitEngine::small()] {
            use crosscheck::engines::Engine;
            group.bench_function(format!("{}/{}", scene.id, engine.name()), |b| {
                b.iter(|| engine.stable_increment(black_box(&scene), &RunSettings::default()))
            });
        }
    }
    group.finish();
}

/// One form of a floor: its name, the duration it runs, and a run of so many increments of h.
type FloorForm = (&'static str, f64, Box<dyn Fn(f64, u64)>);

/// The floors that apply to `scene`, in every form they have: in heap slices
/// (`run::floor::in_slices`), and the damped oscillator's in registers too.
fn floor_forms(scene: &crosscheck::scene::Scene) -> Vec<FloorForm> {
    let mut forms: Vec<FloorForm> = Vec::new();
    if let Some(o) = DampedOscillator::of(scene) {
        let run = move |h, n| {
            black_box(black_box(o).in_registers(h, n));
        };
        forms.push(("registers", o.duration, Box::new(run)));
    }
    if let Some(floor) = floor::in_slices(scene) {
        let duration = floor.duration;
        forms.push(("slices", duration, Box::new(move |h, n| floor.run(h, n))));
    }
    forms
}

fn floor(c: &mut Criterion) {
    let mut group = c.benchmark_group("floor");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(2));
    for scene in seed_cases() {
        let IncrementRule::Given(h) = scene.settings.increment else {
            continue;
        };
        let h = h / REFINEMENT;
        for (form, duration, run) in floor_forms(&scene) {
            let steps = (duration / h).round() as u64;
            group.throughput(Throughput::Elements(steps));
            group.bench_function(format!("{}/{form}", scene.id), |b| {
                b.iter(|| run(black_box(h), steps))
            });
        }
    }
    group.finish();
}

criterion_group!(benches, increment, increment_long, setup, floor);
criterion_main!(benches);
