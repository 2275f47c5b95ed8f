//! An image compare against a render of the same request, timed in turns
//! on all cores: `render` is `/v1/render`'s PNG of the request; `compare`
//! is `/v1/compare`'s whole answer for a port's PNG of it (GL's render,
//! the error, the heatmap, the worst pixels' probes and the diagnosis at
//! the shading points of the pixels that differ and of 65,536 others).
//! The port is glint itself with `"specular_model": "phong"`: Phong's
//! specular differs from GL's on every lit surface, so most of the image's
//! pixels are diagnosed, the costly case.
//!
//! Scenes: the playground's spheres example (640×360, four samples a pixel,
//! shadows, sRGB), and the same at 1920×1080 with one sample.
//!
//! Run: `cargo bench --bench compare_image`; prints the medians and
//! compare ÷ render.

use std::hint::black_box;
use std::time::{Duration, Instant};

use glint::compare::image::compare_image;
use glint::render::render_png;
use glint::scene::{self, Limits};
use serde_json::Value;

/// Rounds of each, in turns.
const ROUNDS: usize = 11;

fn spheres() -> Value {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/spheres.json");
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn median(mut times: Vec<Duration>) -> Duration {
    times.sort();
    times[times.len() / 2]
}

fn main() {
    let mut full_hd = spheres();
    full_hd["camera"]["width"] = 1920.into();
    full_hd["camera"]["height"] = 1080.into();
    full_hd["samples"] = 1.into();
    println!("In turns, {ROUNDS} rounds each, all cores: median of each, and compare ÷ render");
    for (name, request) in [
        ("spheres 640×360, 4 samples", spheres()),
        ("spheres 1920×1080, 1 sample", full_hd),
    ] {
        let body = serde_json::to_vec(&request).unwrap();
        let render = scene::parse_render(&body, &Limits::default()).unwrap();
        let mut port = request.clone();
        port["light_model"]["specular_model"] = "phong".into();
        let port =
            scene::parse_render(&serde_json::to_vec(&port).unwrap(), &Limits::default()).unwrap();
        let candidate = render_png(&port);
        let compared = scene::parse_compare_image(&body, &candidate, &Limits::default()).unwrap();
        let answer = compare_image(&compared, &|| false).unwrap().response;
        let best = &answer.diagnosis[0];
        let found = if best.deviations == ["phong_specular"] && best.explains {
            "found".to_owned()
        } else {
            format!("NOT found: first {:?}", best.deviations)
        };
        let (mut renders, mut compares) = (Vec::new(), Vec::new());
        for _ in 0..ROUNDS {
            let start = Instant::now();
            black_box(render_png(&render));
            renders.push(start.elapsed());
            let start = Instant::now();
            black_box(compare_image(&compared, &|| false));
            compares.push(start.elapsed());
        }
        let (render_time, compare_time) = (median(renders), median(compares));
        println!(
            "{name:<28} render {:>8.2} ms  compare {:>8.2} ms  ratio {:.2} ({} of {} pixels diagnosed; phong_specular {found})",
            render_time.as_secs_f64() * 1e3,
            compare_time.as_secs_f64() * 1e3,
            compare_time.as_secs_f64() / render_time.as_secs_f64(),
            answer.stats.pixels_diagnosed,
            answer.stats.pixels,
        );
    }
}
