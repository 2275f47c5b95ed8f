//! glint's renderer against the renderer a user would pick instead: Mesa's
//! llvmpipe, GL's own rasterizer, drawing the same frame in the same run.
//!
//! The frame: a UV sphere of 10k, 100k or 1M triangles with vertex normals
//! filling most of a 1920×1080 image, one positional light with
//! attenuation, a specular material, no shadows, one sample per pixel.
//! Mesa draws it lit per vertex with GL's fixed-function lighting (Gouraud),
//! and lit per fragment by a GLSL program with the same equation and state
//! (`benches/render_mesa.py`): `glClear`, `glDrawElements` from buffer
//! objects uploaded once, timed to `glFinish`, through OSMesa (llvmpipe on
//! every core). glint renders it `per_vertex` and `per_pixel` (its f32
//! `accurate` tier) from the validated scene to the finished RGBA image: the
//! acceleration structure, the vertex colours and every pixel, on every
//! core; not the PNG, which GL does not make either.
//!
//! The four are timed in turns, round after round (after untimed rounds
//! that warm both sides alike), so that the machine's drift weighs on all
//! alike; the table gives the medians and glint's ratios to Mesa's frame
//! lit the same way (and `per_pixel`'s to Mesa's per-vertex frame too). As
//! a check that each pair drew the same frame, it gives the share of
//! pixels whose 8-bit channels differ by more than 2 between Mesa's image
//! and glint's (they differ at the sphere's outline, where the two sample
//! edges with different arithmetic).
//!
//! Beside them, in the same turns, the BVH that the frame would need with
//! shadows: built for shadow rays alone (the primary rays rasterized), and
//! built as the traced frame needs it for its primary rays, the structure
//! every render built before primary rays were rasterized. Each is the
//! geometry and the BVH from the validated scene.
//!
//! `cargo bench --bench render_mesa` writes `docs/render.md`. Needs Debian's
//! `libosmesa6` and, from PyPI, `PyOpenGL==3.1.10` and `numpy==2.2.6`;
//! without them it stops and says so. `GLINT_RENDER_MESA_ROUNDS` sets the
//! rounds (default 9), `GLINT_RENDER_MESA_SIZES` how many of the sizes to
//! run, smallest first (default all three).

use std::io::{BufRead, BufReader, Write};
use std::path::Path;
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};
use std::time::Instant;

use glint::scene::{self, Limits};
use glint_trace::bvh::BvhUse;
use glint_trace::geometry::Geometry;
use glint_trace::{RenderScene, Renderer};
use serde_json::{Value, json};

mod common;

/// The service's allocator (see `src/main.rs`): a frame's buffers are
/// allocated as the server allocates them.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

const WIDTH: u32 = 1920;
const HEIGHT: u32 = 1080;

/// (segments, rings) of each UV sphere: `2·segments·(rings − 1)` triangles.
const SPHERES: [(u32, u32); 3] = [(100, 51), (320, 161), (1000, 501)];

/// Untimed rounds before the timed ones, the same turns for both sides:
/// llvmpipe compiles its shaders and fills its caches in its first frames,
/// and glint's first frames in a process meet fresh pages and idle
/// threads (at 10,000 triangles, its first two rounds took three times
/// the later ones).
const WARM_ROUNDS: usize = 3;

const INSTALL: &str = "apt-get install libosmesa6 && pip install PyOpenGL==3.1.10 numpy==2.2.6";

/// The GL state of the frame, in glint's request and in Mesa's calls.
const EYE: [f64; 3] = [0.0, 0.8, 3.2];
const TARGET: [f64; 3] = [0.0, 0.0, 0.0];
const UP: [f64; 3] = [0.0, 1.0, 0.0];
const FOV_Y: f64 = 45.0;
const BACKGROUND: [f64; 4] = [0.1, 0.1, 0.12, 1.0];
const LIGHT_MODEL_AMBIENT: [f64; 4] = [0.2, 0.2, 0.2, 1.0];

fn light() -> Value {
    json!({
        "position": [2.0, 3.0, 4.0, 1.0],
        "ambient": [0.0, 0.0, 0.0, 1.0],
        "diffuse": [1.0, 1.0, 1.0, 1.0],
        "specular": [1.0, 1.0, 1.0, 1.0],
        "attenuation": [1.0, 0.02, 0.005],
    })
}

fn material() -> Value {
    json!({
        "ambient": [0.25, 0.2, 0.07, 1.0],
        "diffuse": [0.75, 0.6, 0.23, 1.0],
        "specular": [0.6, 0.55, 0.4, 1.0],
        "emission": [0.0, 0.0, 0.0, 1.0],
        "shininess": 50.0,
    })
}

/// glint's request for the sphere, validated as `/v1/render` would
/// (without the vertex limit).
fn glint_scene(positions: &[[f64; 3]], indices: &[u32], shading: &str) -> RenderScene {
    let request = json!({
        "light_model": { "ambient": LIGHT_MODEL_AMBIENT, "local_viewer": false,
                         "normalize_normals": true },
        "materials": { "gold": material() },
        "lights": [light()],
        "camera": { "eye": EYE, "target": TARGET, "up": UP, "fov_y": FOV_Y,
                    "width": WIDTH, "height": HEIGHT },
        "objects": [{ "mesh": { "positions": positions, "normals": positions,
                                "indices": indices },
                      "material": "gold" }],
        "background": BACKGROUND,
        "shading": shading,
        "samples": 1,
        "shadows": false,
        "precision": "accurate",
    });
    let limits = Limits {
        max_vertices: usize::MAX,
        ..Limits::default()
    };
    scene::parse_render(&serde_json::to_vec(&request).unwrap(), &limits)
        .expect("the bench's request is valid")
}

/// Mesa's side: `benches/render_mesa.py` with the scene loaded, answering
/// one command at a time.
struct Mesa {
    child: Child,
    input: ChildStdin,
    output: BufReader<ChildStdout>,
}

impl Mesa {
    fn start(folder: &Path, positions: &[[f64; 3]], indices: &[u32]) -> Self {
        let floats: Vec<u8> = positions
            .iter()
            .flatten()
            .flat_map(|&c| (c as f32).to_le_bytes())
            .collect();
        std::fs::write(folder.join("positions.f32"), &floats).unwrap();
        std::fs::write(folder.join("normals.f32"), &floats).unwrap();
        let index_bytes: Vec<u8> = indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        std::fs::write(folder.join("indices.u32"), &index_bytes).unwrap();
        let distance = EYE.iter().map(|c| c * c).sum::<f64>().sqrt();
        let state = json!({
            "width": WIDTH, "height": HEIGHT,
            "eye": EYE, "target": TARGET, "up": UP, "fov_y": FOV_Y,
            "near": (distance - 1.5).max(0.05), "far": distance + 1.5,
            "light_model_ambient": LIGHT_MODEL_AMBIENT, "local_viewer": false,
            "light": light(), "material": material(), "background": BACKGROUND,
        });
        std::fs::write(folder.join("scene.json"), state.to_string()).unwrap();
        let script = format!("{}/benches/render_mesa.py", env!("CARGO_MANIFEST_DIR"));
        let mut child = Command::new("python3")
            .arg(script)
            .arg(folder)
            .env("PYOPENGL_PLATFORM", "osmesa")
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()
            .unwrap_or_else(|e| panic!("render_mesa needs python3 ({e}): {INSTALL}"));
        let input = child.stdin.take().unwrap();
        let output = BufReader::new(child.stdout.take().unwrap());
        let mut mesa = Self {
            child,
            input,
            output,
        };
        let first = mesa.line();
        assert!(
            first == "ready",
            "Mesa did not start: {first}\nrender_mesa needs: {INSTALL}"
        );
        mesa
    }

    fn line(&mut self) -> String {
        let mut line = String::new();
        self.output.read_line(&mut line).unwrap();
        line.trim().to_owned()
    }

    fn ask(&mut self, command: &str) -> String {
        writeln!(self.input, "{command}").unwrap();
        self.input.flush().unwrap();
        self.line()
    }

    /// One frame drawn, lit per `mode` (`vertex` or `fragment`), in
    /// milliseconds.
    fn draw(&mut self, mode: &str) -> f64 {
        self.ask(&format!("draw {mode}"))
            .parse()
            .expect("Mesa answers a time")
    }

    /// The last frame's RGBA8 pixels, top row first.
    fn image(&mut self, folder: &Path) -> Vec<u8> {
        let path = folder.join("mesa.rgba");
        assert_eq!(self.ask(&format!("read {}", path.display())), "read");
        std::fs::read(path).unwrap()
    }
}

impl Drop for Mesa {
    fn drop(&mut self) {
        let _ = writeln!(self.input, "quit");
        let _ = self.child.wait();
    }
}

/// glint's frame from the validated scene: the time and the pixels.
fn glint_frame(scene: &RenderScene) -> (f64, f64, Vec<u8>) {
    let started = Instant::now();
    let renderer = Renderer::new(scene);
    let build = renderer.build_time().as_secs_f64() * 1e3;
    let frame = renderer.render(false, &|| false).expect("never cancelled");
    (started.elapsed().as_secs_f64() * 1e3, build, frame.rgba)
}

/// The median of the timed rounds, those after the [`WARM_ROUNDS`].
fn median(mut values: Vec<f64>) -> f64 {
    values.drain(..WARM_ROUNDS);
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// The share of pixels some RGB channel of which differs by more than 2.
fn differing(a: &[u8], b: &[u8]) -> f64 {
    let differ = a
        .chunks_exact(4)
        .zip(b.chunks_exact(4))
        .filter(|(p, q)| (0..3).any(|k| p[k].abs_diff(q[k]) > 2))
        .count();
    differ as f64 / (a.len() / 4) as f64
}

/// The geometry and its BVH for `usage`, in milliseconds.
fn bvh_build(scene: &RenderScene, usage: BvhUse) -> f64 {
    let started = Instant::now();
    let geometry = Geometry::new(&scene.objects);
    geometry.build_bvh(usage);
    let ms = started.elapsed().as_secs_f64() * 1e3;
    drop(geometry);
    ms
}

struct Row {
    triangles: usize,
    shadow_bvh: f64,
    primary_bvh: f64,
    mesa_vertex: f64,
    mesa_fragment: f64,
    per_vertex: f64,
    per_vertex_build: f64,
    per_pixel: f64,
    per_pixel_build: f64,
    /// Between Mesa's and glint's images lit per vertex, and per pixel.
    vertex_differing: f64,
    fragment_differing: f64,
}

fn main() {
    let rounds: usize = std::env::var("GLINT_RENDER_MESA_ROUNDS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(9);
    let folder = std::env::temp_dir().join(format!("glint-render-mesa-{}", std::process::id()));
    std::fs::create_dir_all(&folder).unwrap();
    let sizes: usize = std::env::var("GLINT_RENDER_MESA_SIZES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(SPHERES.len());
    let mut rows = Vec::new();
    for &(segments, rings) in SPHERES.iter().take(sizes) {
        let (positions, indices) = common::uv_sphere(segments, rings);
        let per_vertex = glint_scene(&positions, &indices, "per_vertex");
        let per_pixel = glint_scene(&positions, &indices, "per_pixel");
        let mut mesa = Mesa::start(&folder, &positions, &indices);
        let (mut mesa_vertex, mut mesa_fragment) = (Vec::new(), Vec::new());
        let (mut vertex_ms, mut pixel_ms) = (Vec::new(), Vec::new());
        let (mut vertex_build, mut pixel_build) = (Vec::new(), Vec::new());
        let (mut shadow_bvh, mut primary_bvh) = (Vec::new(), Vec::new());
        let (mut vertex_image, mut pixel_image) = (Vec::new(), Vec::new());
        for _ in 0..WARM_ROUNDS + rounds {
            mesa_vertex.push(mesa.draw("vertex"));
            let (ms, build, rgba) = glint_frame(&per_vertex);
            vertex_ms.push(ms);
            vertex_build.push(build);
            vertex_image = rgba;
            mesa_fragment.push(mesa.draw("fragment"));
            let (ms, build, rgba) = glint_frame(&per_pixel);
            pixel_ms.push(ms);
            pixel_build.push(build);
            pixel_image = rgba;
            shadow_bvh.push(bvh_build(&per_pixel, BvhUse::ShadowRays));
            primary_bvh.push(bvh_build(&per_pixel, BvhUse::PrimaryRays));
        }
        // Mesa's last frame is lit per fragment; one more per vertex.
        let fragment_differing = differing(&mesa.image(&folder), &pixel_image);
        mesa.draw("vertex");
        let vertex_differing = differing(&mesa.image(&folder), &vertex_image);
        let row = Row {
            triangles: indices.len() / 3,
            shadow_bvh: median(shadow_bvh),
            primary_bvh: median(primary_bvh),
            mesa_vertex: median(mesa_vertex),
            mesa_fragment: median(mesa_fragment),
            per_vertex: median(vertex_ms),
            per_vertex_build: median(vertex_build),
            per_pixel: median(pixel_ms),
            per_pixel_build: median(pixel_build),
            vertex_differing,
            fragment_differing,
        };
        println!(
            "{} triangles: Mesa per vertex {:.1} ms, glint per_vertex {:.1} ms (build {:.1}), {:.3}% of pixels differ; Mesa per fragment {:.1} ms, glint per_pixel {:.1} ms (build {:.1}), {:.3}% of pixels differ; BVH for shadows {:.1} ms, for primary rays {:.1} ms",
            row.triangles,
            row.mesa_vertex,
            row.per_vertex,
            row.per_vertex_build,
            row.vertex_differing * 100.0,
            row.mesa_fragment,
            row.per_pixel,
            row.per_pixel_build,
            row.fragment_differing * 100.0,
            row.shadow_bvh,
            row.primary_bvh,
        );
        rows.push(row);
    }
    let _ = std::fs::remove_dir_all(&folder);
    let table = markdown(&rows, rounds);
    println!("{table}");
    let docs = format!("{}/docs", env!("CARGO_MANIFEST_DIR"));
    std::fs::write(format!("{docs}/render.md"), table).unwrap();
    println!("wrote docs/render.md");
}

fn markdown(rows: &[Row], rounds: usize) -> String {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let cpu = common::cpu_model();
    let mut out = format!(
        "# glint's renders against Mesa's rasterizer\n\n\
         Made by `cargo bench --bench render_mesa` on {cores} cores ({cpu}): a UV sphere with \
         vertex normals filling most of a {WIDTH}×{HEIGHT} image, one positional light with \
         attenuation, a specular material, no shadows, one sample per pixel. Mesa's llvmpipe \
         (OSMesa, all cores) draws it lit per vertex, with GL's fixed-function lighting, and \
         lit per fragment, with a GLSL program of the same equation reading the same GL state \
         (`benches/render_mesa.py`): `glClear` and `glDrawElements` from buffer objects, timed \
         to `glFinish`. glint renders it from the validated scene to the finished image \
         (acceleration structure, vertex colours and every pixel, all cores; not the PNG), \
         `per_vertex` and `per_pixel` at the `accurate` tier, with the service's allocator \
         (mimalloc). `per_vertex` pixels come from the rasterizer's decision without a ray \
         (docs/design.md, \"One Gouraud sample per pixel needs no ray\"); `per_pixel` ones \
         from the exact test of each pixel's ray, on the triangle the rasterizer decided alone \
         where it decided one (\"One lit sample per pixel tests one triangle\"). \
         The four take turns, {rounds} rounds after {WARM_ROUNDS} untimed ones; each \
         figure is the median. Each of glint's \
         frames is compared with Mesa's frame lit the same way, and `per_pixel` with Mesa's \
         per-vertex frame too (*÷ per vertex*), the cheaper frame GL's fixed function draws. \
         *Build* is the part of glint's time spent preparing the scene (its acceleration \
         structure and lighting kernels). *Differing*: the share of pixels of the two images \
         with a channel more than 2/255 apart, at the sphere's outline where each samples \
         edges with its own arithmetic.\n\n\
         ### Lit per vertex\n\n\
         | triangles | Mesa ms | glint per_vertex ms (build) | ÷ Mesa | differing |\n\
         | ---: | ---: | ---: | ---: | ---: |\n"
    );
    for r in rows {
        out += &format!(
            "| {} | {:.1} | {:.1} ({:.1}) | {:.2} | {:.2}% |\n",
            r.triangles,
            r.mesa_vertex,
            r.per_vertex,
            r.per_vertex_build,
            r.per_vertex / r.mesa_vertex,
            r.vertex_differing * 100.0,
        );
    }
    out += "\n### Lit per pixel\n\n\
        | triangles | Mesa per fragment ms | glint per_pixel ms (build) | ÷ Mesa | ÷ per vertex | differing |\n\
        | ---: | ---: | ---: | ---: | ---: | ---: |\n";
    for r in rows {
        out += &format!(
            "| {} | {:.1} | {:.1} ({:.1}) | {:.2} | {:.2} | {:.2}% |\n",
            r.triangles,
            r.mesa_fragment,
            r.per_pixel,
            r.per_pixel_build,
            r.per_pixel / r.mesa_fragment,
            r.per_pixel / r.mesa_vertex,
            r.fragment_differing * 100.0,
        );
    }
    out += "\n## The BVH of a frame with shadows\n\n\
        The geometry and BVH from the validated scene, in the same turns: built for the shadow \
        rays alone (the primary rays rasterized: a binary LBVH, Morton-sorted and split at \
        spatial medians in parallel), and as a frame whose primary rays are traced builds it \
        (`obvhs`'s PLOC with reinsertion, the eight-wide CWBVH and its nodes decoded for \
        packets), which every render built before primary rays were rasterized.\n\n\
        | triangles | for shadow rays ms | for primary rays ms | ratio |\n\
        | ---: | ---: | ---: | ---: |\n";
    for r in rows {
        out += &format!(
            "| {} | {:.1} | {:.1} | {:.2} |\n",
            r.triangles,
            r.shadow_bvh,
            r.primary_bvh,
            r.shadow_bvh / r.primary_bvh
        );
    }
    out
}
