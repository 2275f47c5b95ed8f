//! The speed-for-accuracy trade of `/v1/render`: for each example scene
//! (`examples/spheres.json`, `examples/mesh.json`), each shading mode
//! (`per_pixel`, `per_vertex`), 1, 4, 16 and 64 samples per pixel and
//! adaptive sampling to a tolerance of 1/255 (at most 64 samples), and each
//! precision tier, the render time on all cores (the median of a few runs
//! of what the response reports as `stats.render_ms`: tracing and lighting,
//! the Gouraud vertex colours included, not the acceleration structures nor
//! the PNG) and the error of the image against the ground truth, a 64-sample
//! `per_pixel` render at `reference` precision: the PSNR of the 8-bit RGB
//! channels, encoded linearly (round(255·c), whatever the request's
//! `encoding`). Spheres and planes have no vertices and are lit per pixel in
//! both modes. The samplings of one scene, shading and tier take turns, run
//! after run, so that the machine's drift weighs on all alike. Writes
//! `docs/render_trade.md` and the chart `docs/render_trade.svg`, and checks
//! the goal of adaptive sampling: at least the PSNR of 16 uniform samples
//! in at most a quarter of their time.
//!
//! `cargo bench --bench render_trade` (`GLINT_RENDER_TRADE_WIDTH` and
//! `GLINT_RENDER_TRADE_HEIGHT` set the image size, 640×360 by default).

use std::time::Duration;

use glint::scene::{self, Limits};
use glint_lighting::Precision;
use glint_trace::{Encoding, RenderScene, Samples, ShadingMode};
use glint_trace::{Frame, Renderer};
use plotters::prelude::*;
use serde_json::json;

mod common;

/// (name, file) of each scene.
const SCENES: [(&str, &str); 2] = [("spheres", "spheres.json"), ("mesh", "mesh.json")];
const SHADINGS: [(&str, ShadingMode); 2] = [
    ("per_pixel", ShadingMode::PerPixel),
    ("per_vertex", ShadingMode::PerVertex),
];
/// The adaptive tolerance: one step of an 8-bit channel.
const TOLERANCE: f64 = 1.0 / 255.0;
const SAMPLES: [Samples; 5] = [
    Samples::Uniform(1),
    Samples::Uniform(4),
    Samples::Uniform(16),
    Samples::Uniform(64),
    Samples::Adaptive {
        max: 64,
        tolerance: TOLERANCE,
    },
];
const TIERS: [(&str, Precision); 3] = [
    ("reference", Precision::Reference),
    ("accurate", Precision::Accurate),
    ("fast", Precision::Fast),
];
/// Timed runs per measurement; the median is kept.
const RUNS: usize = 5;

struct Row {
    scene: &'static str,
    shading: &'static str,
    samples: Samples,
    /// Samples per pixel, on average.
    mean_samples: f64,
    tier: &'static str,
    seconds: f64,
    psnr: f64,
}

/// The samples' name in the table.
fn label(samples: Samples) -> String {
    match samples {
        Samples::Uniform(n) => n.to_string(),
        Samples::Adaptive { max, .. } => format!("adaptive ≤{max}"),
    }
}

fn main() {
    let size = |name: &str, default: u32| -> u32 {
        std::env::var(name)
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(default)
    };
    let width = size("GLINT_RENDER_TRADE_WIDTH", 640);
    let height = size("GLINT_RENDER_TRADE_HEIGHT", 360);
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());

    let mut rows = Vec::new();
    for (name, file) in SCENES {
        let base = load(file, width, height);
        let truth = render(&with(
            &base,
            ShadingMode::PerPixel,
            Samples::Uniform(64),
            Precision::Reference,
        ))
        .0
        .rgba;
        for (shading_name, shading) in SHADINGS {
            for (tier_name, tier) in TIERS {
                let scenes: Vec<RenderScene> = SAMPLES
                    .iter()
                    .map(|&samples| with(&base, shading, samples, tier))
                    .collect();
                let mut times = vec![Vec::with_capacity(RUNS); scenes.len()];
                let mut frames = vec![None; scenes.len()];
                for _ in 0..RUNS {
                    for (k, scene) in scenes.iter().enumerate() {
                        let (frame, time) = render(scene);
                        times[k].push(time.as_secs_f64());
                        frames[k] = Some(frame);
                    }
                }
                for ((scene, mut times), frame) in scenes.iter().zip(times).zip(frames) {
                    let frame = frame.expect("rendered");
                    times.sort_by(f64::total_cmp);
                    rows.push(Row {
                        scene: name,
                        shading: shading_name,
                        samples: scene.samples,
                        mean_samples: frame.sampling.mean,
                        tier: tier_name,
                        seconds: times[RUNS / 2],
                        psnr: psnr(&frame.rgba, &truth),
                    });
                }
            }
        }
    }

    let table = markdown(&rows, width, height, cores);
    println!("{table}");
    let docs = format!("{}/docs", env!("CARGO_MANIFEST_DIR"));
    std::fs::create_dir_all(&docs).unwrap();
    std::fs::write(format!("{docs}/render_trade.md"), &table).unwrap();
    chart(&rows, &format!("{docs}/render_trade.svg")).unwrap();
    println!("wrote docs/render_trade.md and docs/render_trade.svg");
    for goal in goals(&rows) {
        println!(
            "adaptive against 16 samples, {} {} {}: PSNR {:.1} / {:.1} dB, time ratio {:.2}: {}",
            goal.scene,
            goal.shading,
            goal.tier,
            goal.adaptive.psnr,
            goal.uniform.psnr,
            goal.adaptive.seconds / goal.uniform.seconds,
            if goal.met() { "met" } else { "not met" },
        );
    }
}

/// The example request `file` at `width`×`height`, the whole image, no
/// probes, validated as `/v1/render` would (without the vertex limit).
fn load(file: &str, width: u32, height: u32) -> RenderScene {
    let path = format!("{}/examples/{file}", env!("CARGO_MANIFEST_DIR"));
    let mut request: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).expect("the example exists"))
            .expect("the example is JSON");
    request["camera"]["width"] = json!(width);
    request["camera"]["height"] = json!(height);
    let object = request.as_object_mut().unwrap();
    object.remove("region");
    object.remove("probes");
    let limits = Limits {
        max_vertices: usize::MAX,
        ..Limits::default()
    };
    scene::parse_render(&serde_json::to_vec(&request).unwrap(), &limits)
        .expect("the example is a valid render request")
}

fn with(
    base: &RenderScene,
    shading: ShadingMode,
    samples: Samples,
    precision: Precision,
) -> RenderScene {
    RenderScene {
        shading,
        samples,
        precision,
        encoding: Encoding::Linear,
        ..base.clone()
    }
}

/// The frame of `scene` on all cores, and its render time.
fn render(scene: &RenderScene) -> (Frame, Duration) {
    let frame = Renderer::new(scene)
        .render(false, &|| false)
        .expect("never cancelled");
    let time = frame.render_time;
    (frame, time)
}

/// 10·log10(255² / MSE) over the RGB channels; infinite for equal images.
fn psnr(image: &[u8], truth: &[u8]) -> f64 {
    let (mut sum, mut channels) = (0.0f64, 0usize);
    for (a, b) in image.chunks_exact(4).zip(truth.chunks_exact(4)) {
        for k in 0..3 {
            sum += (f64::from(a[k]) - f64::from(b[k])).powi(2);
            channels += 1;
        }
    }
    10.0 * (255.0f64.powi(2) / (sum / channels as f64)).log10()
}

fn markdown(rows: &[Row], width: u32, height: u32, cores: usize) -> String {
    let cpu = common::cpu_model();
    let mut out = format!(
        "# The speed-for-accuracy trade of `/v1/render`\n\n\
         Made by `cargo bench --bench render_trade` on {cores} cores ({cpu}), the example \
         scenes at {width}×{height}, the median of {RUNS} runs of the render time \
         (`stats.render_ms`: tracing and lighting, the Gouraud vertex colours included; not the \
         acceleration structures nor the PNG); the samplings of a scene, shading and tier take \
         turns, run after run. PSNR is over the 8-bit RGB channels, encoded linearly, against \
         a 64-sample `per_pixel` render at `reference` precision; spheres and planes are lit \
         per pixel in both modes. *Adaptive* takes each pixel's four corners and its centre, then sets of 16 \
         stratified samples inside the pixels whose estimate has not settled within 1/255 (the \
         standard error of a stratified mean, see `glint_trace::film`), up to 64; its samples \
         per pixel count a corner for each of its four pixels.\n\n\
         | scene | shading | samples | samples per pixel | tier | M pixels/s | ms per frame | PSNR dB vs 64-sample reference |\n\
         | --- | --- | ---: | ---: | --- | ---: | ---: | ---: |\n"
    );
    let pixels = f64::from(width) * f64::from(height);
    for r in rows {
        let psnr = if r.psnr.is_finite() {
            format!("{:.1}", r.psnr)
        } else {
            "∞".to_owned()
        };
        out += &format!(
            "| {} | {} | {} | {:.2} | {} | {:.2} | {:.1} | {psnr} |\n",
            r.scene,
            r.shading,
            label(r.samples),
            r.mean_samples,
            r.tier,
            pixels / r.seconds / 1e6,
            r.seconds * 1e3,
        );
    }
    out += "\n## The goal of adaptive sampling\n\n\
        Adaptive sampling to 1/255 against 16 uniform samples, same scene, shading and tier: \
        it should reach at least their PSNR in at most a quarter of their time.\n\n\
        | scene | shading | tier | PSNR dB, adaptive / 16 | ms, adaptive / 16 | time ratio | met |\n\
        | --- | --- | --- | ---: | ---: | ---: | --- |\n";
    for goal in goals(rows) {
        out += &format!(
            "| {} | {} | {} | {:.1} / {:.1} | {:.1} / {:.1} | {:.2} | {} |\n",
            goal.scene,
            goal.shading,
            goal.tier,
            goal.adaptive.psnr,
            goal.uniform.psnr,
            goal.adaptive.seconds * 1e3,
            goal.uniform.seconds * 1e3,
            goal.adaptive.seconds / goal.uniform.seconds,
            if goal.met() { "yes" } else { "no" },
        );
    }
    out
}

/// Adaptive sampling beside 16 uniform samples, for one scene, shading
/// and tier.
struct Goal<'a> {
    scene: &'static str,
    shading: &'static str,
    tier: &'static str,
    adaptive: &'a Row,
    uniform: &'a Row,
}

impl Goal<'_> {
    fn met(&self) -> bool {
        self.adaptive.psnr >= self.uniform.psnr
            && self.adaptive.seconds <= self.uniform.seconds / 4.0
    }
}

fn goals(rows: &[Row]) -> Vec<Goal<'_>> {
    rows.iter()
        .filter(|r| matches!(r.samples, Samples::Adaptive { .. }))
        .filter_map(|adaptive| {
            let uniform = rows.iter().find(|r| {
                r.samples == Samples::Uniform(16)
                    && (r.scene, r.shading, r.tier)
                        == (adaptive.scene, adaptive.shading, adaptive.tier)
            })?;
            Some(Goal {
                scene: adaptive.scene,
                shading: adaptive.shading,
                tier: adaptive.tier,
                adaptive,
                uniform,
            })
        })
        .collect()
}

/// PSNR against ms per frame (log), one colour per tier, a circle for
/// `per_pixel` and a triangle for `per_vertex` (hollow for adaptive
/// sampling), each point labelled with its scene and samples; an infinite
/// PSNR is drawn at the top.
fn chart(rows: &[Row], path: &str) -> Result<(), Box<dyn std::error::Error>> {
    let ms: Vec<f64> = rows.iter().map(|r| r.seconds * 1e3).collect();
    let finite = rows.iter().map(|r| r.psnr).filter(|p| p.is_finite());
    let (x_min, x_max) = (
        ms.iter().copied().fold(f64::INFINITY, f64::min) / 1.5,
        ms.iter().copied().fold(0.0, f64::max) * 1.5,
    );
    let (y_min, y_top) = finite.fold((f64::INFINITY, 0.0f64), |(lo, hi), p| {
        (lo.min(p), hi.max(p))
    });
    let (y_min, y_top) = ((y_min - 3.0).floor(), (y_top + 5.0).ceil());

    let root = SVGBackend::new(path, (1000, 640)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption("glint /v1/render: time against error", ("sans-serif", 22))
        .margin(16)
        .x_label_area_size(48)
        .y_label_area_size(64)
        .build_cartesian_2d((x_min..x_max).log_scale(), y_min..y_top)?;
    chart
        .configure_mesh()
        .x_desc("ms per frame, all cores")
        .y_desc("PSNR dB against the 64-sample reference (∞ at the top)")
        .x_label_formatter(&|x| format!("{x:.0}"))
        .draw()?;
    for (tier, color) in [("reference", BLACK), ("accurate", BLUE), ("fast", RED)] {
        for (shading, _) in SHADINGS {
            let points: Vec<(f64, f64, String, bool)> = rows
                .iter()
                .filter(|r| r.tier == tier && r.shading == shading)
                .map(|r| {
                    let psnr = if r.psnr.is_finite() { r.psnr } else { y_top };
                    let name = format!("{} {}", r.scene, label(r.samples));
                    let adaptive = matches!(r.samples, Samples::Adaptive { .. });
                    (r.seconds * 1e3, psnr, name, adaptive)
                })
                .collect();
            let label_style = ("sans-serif", 10).into_font().color(&color.mix(0.7));
            let triangle = shading == "per_vertex";
            chart
                .draw_series(points.iter().map(|(x, y, label, adaptive)| {
                    let style = if *adaptive {
                        color.stroke_width(2)
                    } else {
                        color.filled()
                    };
                    let marker: DynElement<_, _> = if triangle {
                        TriangleMarker::new((0, 0), 6, style).into_dyn()
                    } else {
                        Circle::new((0, 0), 5, style).into_dyn()
                    };
                    EmptyElement::at((*x, *y))
                        + marker
                        + Text::new(label.clone(), (6, -12), label_style.clone())
                }))?
                .label(format!("{tier}, {shading}"))
                .legend(move |(x, y)| {
                    if triangle {
                        TriangleMarker::new((x, y), 6, color.filled()).into_dyn()
                    } else {
                        Circle::new((x, y), 5, color.filled()).into_dyn()
                    }
                });
        }
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerRight)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    root.present()?;
    Ok(())
}
