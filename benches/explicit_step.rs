//! What a run costs: each engine on representative cases (2D and 3D contact, a damped spring
//! system), the whole run including the stable-increment analysis.
use criterion::{Criterion, criterion_group, criterion_main};
use crosscheck::case;
use crosscheck::engines::{self, RunSettings};
use std::hint::black_box;

fn runs(c: &mut Criterion) {
    let mut group = c.benchmark_group("run");
    group.sample_size(20);
    for id in [
        "rigid2d_pin_lumped",
        "rigid3d_slide_surface",
        "springs_n2n_c",
    ] {
        let scene = case::load(&case::cases_dir().join(format!("{id}.toml"))).unwrap();
        for engine in engines::all() {
            group.bench_function(format!("{id}/{}", engine.name()), |b| {
                b.iter(|| {
                    engine
                        .run(black_box(&scene), &RunSettings::default())
                        .unwrap()
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, runs);
criterion_main!(benches);
