//! Comparing 1e6 vertices against the whole catalogue, beside one shade of
//! the same vertices at the same tier: the goal is a compare within 4× the
//! shade.
//!
//! `cargo bench -p glint-compare --bench compare`
//!
//! The shade is what `/v1/shade` does with a validated scene: prepare the
//! light set, convert the batch, light it into fresh buffers. The compare
//! is `glint_compare::compare`: its own conversion, GL and every deviation
//! the scene can show in one pass, the error figures (the exact p99 and the
//! 10 worst vertices included) and the diagnosis.
//!
//! The scenes (`tests/scenes`, which `tests/diagnosis.rs` tests the
//! diagnosis on):
//! - **every term**: what a port's author compares on, a scene in which
//!   every term of the equation is non-zero, so that the catalogue's
//!   deviations all have something to change (16 of the 21 apply). The
//!   candidate is a port with `phong_specular` (one pass) and one with
//!   `phong_specular` and `attenuation_ignored` (the pairs' second pass).
//! - **1 directional, no specular**: the scene whose shade is fastest (bound
//!   by memory), the hardest ratio to keep; 7 deviations apply. The
//!   candidate is a port with `diffuse_unclamped`, which this scene cannot
//!   show (the light is along +z and every normal within 35° of it, so
//!   `n·VP` is never below 0): it draws GL's colours, and what is expected
//!   is no explanation, the deviation listed as unobservable.
//!
//! After criterion's runs, the same work is timed in turns (shade, compare,
//! shade, …), and the medians and their ratio are printed: the figure to
//! quote, since drift of the machine weighs on both alike.

#[path = "../tests/scenes/mod.rs"]
mod scenes;

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{BenchmarkId, Criterion, Throughput};
use glam::{DVec3, Vec4};
use glint_compare::{Candidate, Comparison, Deviation, Deviations, Options, compare};
use glint_lighting::kernel::{Colors, Kernel};
use glint_lighting::{Precision, Side};
use rayon::prelude::*;
use scenes::{TestScene, every_term, one_directional};

const VERTICES: usize = 1_000_000;

/// A scene and its candidates.
struct Bench {
    name: &'static str,
    scene: TestScene,
    /// (name, the port whose colours the candidate holds, what the
    /// diagnosis should say of it).
    candidates: Vec<(&'static str, Deviations, Expected)>,
}

/// What the diagnosis of a candidate should say.
#[derive(Clone, Copy)]
enum Expected {
    /// The port's deviations come first, and explain the candidate.
    Explained,
    /// The scene cannot show the port's deviations: the candidate is GL's
    /// colours within the bound, nothing explains it, and the deviations
    /// are listed as unobservable.
    Unobservable,
}

impl Expected {
    /// Whether `found`, the comparison of the port with `deviations`, says
    /// what is expected; if not, what it says.
    fn check(self, deviations: Deviations, found: &Comparison) -> Result<(), String> {
        let diagnosis = &found.diagnosis;
        let first = diagnosis.explanations.first();
        let holds = match self {
            Expected::Explained => first.is_some_and(|e| e.deviations == deviations && e.explains),
            Expected::Unobservable => {
                found.error.within_bound
                    && diagnosis.explanations.iter().all(|e| !e.explains)
                    && deviations
                        .iter()
                        .all(|d| diagnosis.unobservable.contains(&d))
            }
        };
        if holds {
            return Ok(());
        }
        Err(match first {
            Some(e) => format!("first {} (explains: {})", e.deviations, e.explains),
            None => "no explanation".to_owned(),
        })
    }

    fn name(self) -> &'static str {
        match self {
            Expected::Explained => "found",
            Expected::Unobservable => "unobservable, as expected",
        }
    }
}

fn every_term_bench() -> Bench {
    Bench {
        name: "every term",
        scene: every_term(VERTICES),
        candidates: vec![
            (
                "phong_specular",
                Deviation::PhongSpecular.into(),
                Expected::Explained,
            ),
            (
                "phong_specular+attenuation_ignored",
                Deviations::of(&[Deviation::PhongSpecular, Deviation::AttenuationIgnored]),
                Expected::Explained,
            ),
        ],
    }
}

fn one_directional_bench() -> Bench {
    Bench {
        name: "1 directional, no specular",
        scene: one_directional(VERTICES, DVec3::Z),
        candidates: vec![(
            "diffuse_unclamped",
            Deviation::DiffuseUnclamped.into(),
            Expected::Unobservable,
        )],
    }
}

impl Bench {
    /// One shade, as `/v1/shade` lights a validated scene.
    fn shade(&self, precision: Precision) -> Colors {
        let scene = &self.scene;
        match precision.tier() {
            Some(tier) => {
                let kernel = Kernel::new(&scene.lights, &scene.positions);
                let products = kernel.products(&scene.material);
                let vertices = kernel.prepare(&scene.positions, &scene.normals);
                kernel.light(tier, &products, &vertices)
            }
            None => Colors {
                front: scene
                    .positions
                    .par_iter()
                    .zip(&scene.normals)
                    .map(|(&p, &n)| {
                        glint_lighting::reference::color(
                            &scene.lights,
                            &scene.material,
                            Side::Front,
                            p,
                            n,
                        )
                        .as_vec4()
                    })
                    .collect(),
                back: None,
            },
        }
    }
}

const TIERS: [(&str, Precision); 3] = [
    ("accurate", Precision::Accurate),
    ("fast", Precision::Fast),
    ("reference", Precision::Reference),
];

fn criterion_runs(c: &mut Criterion, benches: &[(Bench, Vec<Vec<Vec4>>)]) {
    for (bench, candidates) in benches {
        let mut group = c.benchmark_group(bench.name);
        group.throughput(Throughput::Elements(VERTICES as u64));
        group.sample_size(10);
        for (tier, precision) in TIERS {
            group.bench_function(BenchmarkId::new("shade", tier), |b| {
                b.iter(|| black_box(bench.shade(precision)))
            });
            for ((name, ..), colors) in bench.candidates.iter().zip(candidates) {
                let candidate = Candidate {
                    front: colors,
                    back: None,
                    alpha: false,
                };
                group.bench_function(BenchmarkId::new(format!("compare {name}"), tier), |b| {
                    b.iter(|| {
                        black_box(compare(
                            &bench.scene.scene(precision),
                            &candidate,
                            &Options::default(),
                        ))
                    })
                });
            }
        }
        group.finish();
    }
}

fn median(mut times: Vec<Duration>) -> Duration {
    times.sort();
    times[times.len() / 2]
}

/// Shade and compare in turns, `rounds` each; prints the medians and the
/// ratio.
fn in_turns(benches: &[(Bench, Vec<Vec<Vec4>>)]) {
    println!("\nIn turns, {VERTICES} vertices, all cores: median of each, and compare ÷ shade");
    for (bench, candidates) in benches {
        for (tier, precision) in TIERS {
            let rounds = if precision == Precision::Reference {
                5
            } else {
                21
            };
            for ((name, deviations, expected), colors) in bench.candidates.iter().zip(candidates) {
                let candidate = Candidate {
                    front: colors,
                    back: None,
                    alpha: false,
                };
                let scene = bench.scene.scene(precision);
                // Whether what is timed says what is expected of the port
                // (printed, not assumed).
                let found = compare(&scene, &candidate, &Options::default()).unwrap();
                let diagnosed = match expected.check(*deviations, &found) {
                    Ok(()) => expected.name().to_owned(),
                    Err(said) => format!("NOT {}: {said}", expected.name()),
                };
                let (mut shades, mut compares) = (Vec::new(), Vec::new());
                for _ in 0..rounds {
                    let start = Instant::now();
                    black_box(bench.shade(precision));
                    shades.push(start.elapsed());
                    let start = Instant::now();
                    black_box(compare(&scene, &candidate, &Options::default()).unwrap());
                    compares.push(start.elapsed());
                }
                let (shade, compared) = (median(shades), median(compares));
                println!(
                    "{:<28} {:<10} candidate {:<36} shade {:>9.2} ms  compare {:>9.2} ms  ratio {:.2} ({} models, {} pairs; {diagnosed})",
                    bench.name,
                    tier,
                    name,
                    shade.as_secs_f64() * 1e3,
                    compared.as_secs_f64() * 1e3,
                    compared.as_secs_f64() / shade.as_secs_f64(),
                    found.diagnosis.explanations.len() + found.diagnosis.unobservable.len(),
                    found.diagnosis.pairs_tried,
                );
            }
        }
    }
}

fn main() {
    let benches: Vec<(Bench, Vec<Vec<Vec4>>)> = [every_term_bench(), one_directional_bench()]
        .into_iter()
        .map(|bench| {
            let candidates = bench
                .candidates
                .iter()
                .map(|(_, d, _)| bench.scene.port_colors(*d))
                .collect();
            (bench, candidates)
        })
        .collect();
    let mut criterion = Criterion::default().configure_from_args();
    criterion_runs(&mut criterion, &benches);
    criterion.final_summary();
    in_turns(&benches);
}
