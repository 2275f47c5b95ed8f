//! The speed-for-accuracy trade of `/v1/render`: for each example scene
//! (`examples/spheres.json`, `examples/mesh.json`), each shading mode
//! (`per_pixel`, `per_vertex`), 1, 4, 16 and 64 samples per pixel and each
//! precision tier, the render time on all cores (the median of a few runs
//! of what the response reports as `stats.render_ms`: tracing and lighting,
//! the Gouraud vertex colours included, not the BVH build nor the PNG) and
//! the error of the image against the ground truth, a 64-sample `per_pixel`
//! render at `reference` precision: the PSNR of the 8-bit RGB channels,
//! encoded linearly (round(255·c), whatever the request's `encoding`).
//! Spheres and planes have no vertices and are lit per pixel in both modes.
//! Writes `docs/render_trade.md` and the chart `docs/render_trade.svg`.
//!
//! `cargo bench --bench render_trade` (`GLINT_RENDER_TRADE_WIDTH` and
//! `GLINT_RENDER_TRADE_HEIGHT` set the image size, 320×240 by default).

use std::time::Duration;

use glint::scene::{self, Limits};
use glint_lighting::Precision;
use glint_trace::Renderer;
use glint_trace::{Encoding, RenderScene, ShadingMode};
use plotters::prelude::*;
use serde_json::json;

mod common;

/// (name, file) of each scene.
const SCENES: [(&str, &str); 2] = [("spheres", "spheres.json"), ("mesh", "mesh.json")];
const SHADINGS: [(&str, ShadingMode); 2] = [
    ("per_pixel", ShadingMode::PerPixel),
    ("per_vertex", ShadingMode::PerVertex),
];
const SAMPLES: [u32; 4] = [1, 4, 16, 64];
const TIERS: [(&str, Precision); 3] = [
    ("reference", Precision::Reference),
    ("accurate", Precision::Accurate),
    ("fast", Precision::Fast),
];
/// Timed runs per measurement; the median is kept.
const RUNS: usize = 3;

struct Row {
    scene: &'static str,
    shading: &'static str,
    samples: u32,
    tier: &'static str,
    seconds: f64,
    psnr: f64,
}

fn main() {
    let size = |name: &str, default: u32| -> u32 {
        std::env::var(name)
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(default)
    };
    let width = size("GLINT_RENDER_TRADE_WIDTH", 320);
    let height = size("GLINT_RENDER_TRADE_HEIGHT", 240);
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());

    let mut rows = Vec::new();
    for (name, file) in SCENES {
        let base = load(file, width, height);
        let truth = render(&with(
            &base,
            ShadingMode::PerPixel,
            64,
            Precision::Reference,
        ))
        .0;
        for (shading_name, shading) in SHADINGS {
            for samples in SAMPLES {
                for (tier_name, tier) in TIERS {
                    let scene = with(&base, shading, samples, tier);
                    let mut times = Vec::with_capacity(RUNS);
                    let mut image = Vec::new();
                    for _ in 0..RUNS {
                        let (rgba, time) = render(&scene);
                        times.push(time.as_secs_f64());
                        image = rgba;
                    }
                    times.sort_by(f64::total_cmp);
                    rows.push(Row {
                        scene: name,
                        shading: shading_name,
                        samples,
                        tier: tier_name,
                        seconds: times[RUNS / 2],
                        psnr: psnr(&image, &truth),
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
    samples: u32,
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

/// The RGBA8 image of `scene` on all cores, and its render time.
fn render(scene: &RenderScene) -> (Vec<u8>, Duration) {
    let frame = Renderer::new(scene)
        .render(false, &|| false)
        .expect("never cancelled");
    (frame.rgba, frame.render_time)
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
         BVH build nor the PNG). PSNR is over the 8-bit RGB channels, encoded linearly, against \
         a 64-sample `per_pixel` render at `reference` precision; spheres and planes are lit \
         per pixel in both modes.\n\n\
         | scene | shading | samples | tier | M pixels/s | ms per frame | PSNR dB vs 64-sample reference |\n\
         | --- | --- | ---: | --- | ---: | ---: | ---: |\n"
    );
    let pixels = f64::from(width) * f64::from(height);
    for r in rows {
        let psnr = if r.psnr.is_finite() {
            format!("{:.1}", r.psnr)
        } else {
            "∞".to_owned()
        };
        out += &format!(
            "| {} | {} | {} | {} | {:.2} | {:.1} | {psnr} |\n",
            r.scene,
            r.shading,
            r.samples,
            r.tier,
            pixels / r.seconds / 1e6,
            r.seconds * 1e3,
        );
    }
    out
}

/// PSNR against ms per frame (log), one colour per tier, a circle for
/// `per_pixel` and a triangle for `per_vertex`, each point labelled with
/// its scene and samples; an infinite PSNR is drawn at the top.
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
            let points: Vec<(f64, f64, String)> = rows
                .iter()
                .filter(|r| r.tier == tier && r.shading == shading)
                .map(|r| {
                    let psnr = if r.psnr.is_finite() { r.psnr } else { y_top };
                    let label = format!("{} {}", r.scene, r.samples);
                    (r.seconds * 1e3, psnr, label)
                })
                .collect();
            let label_style = ("sans-serif", 10).into_font().color(&color.mix(0.7));
            let triangle = shading == "per_vertex";
            chart
                .draw_series(points.iter().map(|(x, y, label)| {
                    let marker: DynElement<_, _> = if triangle {
                        TriangleMarker::new((0, 0), 6, color.filled()).into_dyn()
                    } else {
                        Circle::new((0, 0), 5, color.filled()).into_dyn()
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
