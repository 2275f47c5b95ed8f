//! The page in headless Chromium against the real binary: `e2e.mjs` loads
//! it, moves its controls, clicks a pixel, sends a bad value, compares two
//! tiers, copies a request as curl, and renders and bakes a GLB that this
//! test builds, comparing what the page shows with the API's answers. The
//! baked models the page offers for download are checked here: the Khronos
//! glTF validator finds no error in them, and their `COLOR_0` is glint's
//! JSON answer for the same vertices (read from the model and placed by
//! the test's own matrices) and the same lighting, stored as the contract
//! says. It writes a screenshot to `target/playground/`; an
//! optimised build (`cargo test --release`) also puts it in
//! `docs/playground.png` when the page looks different from the one there
//! (the page shows the server's times, and a build without optimisations
//! would show times, and a trade between tiers, no user sees).

use std::path::{Path, PathBuf};
use std::time::Duration;

use serde_json::{Value, json};

use super::{Browser, loud, repo, run, target};
use crate::clients::gltf::khronos_reports;
use crate::gltf::bake::{TENT, TENT_INDICES};
use crate::gltf::support::{Gltf, normal, point, read_glb, srgb_to_linear, trs, unit};
use crate::load::Glint;
use crate::support::client;

/// Where the page's model stands: away from the origin, where no example's
/// camera looks, so that only a camera that frames it sees it.
const TENT_TRANSLATION: [f64; 3] = [10.0, -2.0, -5.0];
const TENT_SCALE: [f64; 3] = [2.0, 2.0, 2.0];
/// The tent's glTF material, `clay`: its base colour, metallic and
/// roughness factors (a broad highlight, which the vertices catch; numbers
/// whose powers are exact).
const CLAY: [f64; 4] = [0.8, 0.35, 0.2, 1.0];
const CLAY_METALLIC: f64 = 0.5;
const CLAY_ROUGHNESS: f64 = 0.75;

/// The GLB the page is given: the tent, with normals leaning out, one
/// material and a node that moves and scales it.
fn tent() -> Vec<u8> {
    let mut g = Gltf::new();
    let normals: Vec<[f32; 3]> = TENT
        .iter()
        .map(|p| unit([f64::from(p[0]), 0.5, f64::from(p[2])]).map(|x| x as f32))
        .collect();
    let positions = g.vec3s(&TENT);
    let normals = g.vec3s(&normals);
    let indices = g.indices(&TENT_INDICES, 5123);
    let clay = g.material(json!({
        "name": "clay",
        "pbrMetallicRoughness": {
            "baseColorFactor": CLAY, "metallicFactor": CLAY_METALLIC, "roughnessFactor": CLAY_ROUGHNESS
        }
    }));
    let mesh = g.mesh(json!([{
        "attributes": { "POSITION": positions, "NORMAL": normals },
        "indices": indices, "material": clay
    }]));
    let node =
        g.node(json!({ "mesh": mesh, "translation": TENT_TRANSLATION, "scale": TENT_SCALE }));
    g.scene(&[node]);
    g.glb()
}

/// The GL material the contract maps `clay` to when the request names
/// none (api/openapi.yaml, "glTF 2.0 models", materials): diffuse = ambient
/// = baseColorFactor, specular = mix(0.04, baseColorFactor, metallic) ·
/// (1 − roughness), shininess = 2/roughness⁴ − 2, no emission.
fn clay_as_gl() -> Value {
    let specular = |c: f64| (0.04 + (c - 0.04) * CLAY_METALLIC) * (1.0 - CLAY_ROUGHNESS);
    json!({
        "ambient": CLAY,
        "diffuse": CLAY,
        "specular": [specular(CLAY[0]), specular(CLAY[1]), specular(CLAY[2]), 1.0],
        "emission": [0.0, 0.0, 0.0, 1.0],
        "shininess": 2.0 / CLAY_ROUGHNESS.powi(4) - 2.0,
    })
}

#[tokio::test]
async fn the_page_in_a_browser() {
    let Some(tools) = Browser::get("playground::browser::the_page_in_a_browser").await else {
        return;
    };
    let glint = Glint::spawn(&[]).await;
    let out = target().join("playground");
    std::fs::create_dir_all(&out).unwrap();
    let shot = out.join("playground.png");
    let _ = std::fs::remove_file(&shot);
    let model = out.join("tent.glb");
    std::fs::write(&model, tent()).unwrap();
    // What the page will download, from no earlier run.
    let bakes = ["tent-baked", "tent-baked-own"];
    for name in bakes {
        let _ = std::fs::remove_file(out.join(format!("{name}.glb")));
        let _ = std::fs::remove_file(out.join(format!("{name}.request.json")));
    }
    let script = repo().join("tests/playground/e2e.mjs");
    let output = run(
        "node",
        &[script.as_os_str()],
        |c| {
            c.env("GLINT_BASE", glint.url(""))
                .env("GLINT_PLAYWRIGHT_DIR", tools.playwright.dir())
                .env("GLINT_CHROMIUM", &tools.chromium)
                .env("GLINT_EXAMPLES", repo().join("examples"))
                .env("GLINT_MODEL", &model)
                .env("GLINT_OUT", &out)
                .env("GLINT_SCREENSHOT", &shot);
        },
        Duration::from_secs(240),
    )
    .await
    .unwrap_or_else(|e| panic!("{e}\nglint's log:\n{}", glint.logs()));
    let printed = String::from_utf8_lossy(&output.stdout);
    eprintln!("{printed}");
    assert!(
        printed.contains("playground: every check passed"),
        "{printed}"
    );

    // The downloads: what the server's mapping of the model's material
    // bakes, and what a GL material of the page's own bakes.
    let files: Vec<PathBuf> = bakes
        .iter()
        .map(|name| out.join(format!("{name}.glb")))
        .collect();
    for (file, name) in files.iter().zip(bakes) {
        let baked = std::fs::read(file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        let sent = out.join(format!("{name}.request.json"));
        let sent: Value = serde_json::from_slice(&std::fs::read(&sent).unwrap()).unwrap();
        let material = match name {
            "tent-baked" => {
                assert_eq!(sent.get("materials"), None, "the page named no material");
                clay_as_gl()
            }
            _ => sent["materials"]["#0"].clone(),
        };
        assert!(material.is_object(), "{name}: {sent}");
        colors_are_the_json_answer(&glint, name, &baked, &sent, material).await;
    }
    if let Some(reports) =
        khronos_reports(&files, "playground::browser::the_page_in_a_browser").await
    {
        for file in &files {
            let report = &reports[file.to_str().unwrap()];
            assert_eq!(report["errors"], 0, "{}: {report}", file.display());
        }
    }

    let new = image::open(&shot)
        .unwrap_or_else(|e| panic!("the test's screenshot {}: {e}", shot.display()))
        .to_rgba8();
    assert_eq!(new.dimensions(), (1280, 800), "the screenshot's size");
    let docs = repo().join("docs/playground.png");
    if !cfg!(debug_assertions) && looks_different(&new, &docs) {
        std::fs::copy(&shot, &docs).unwrap_or_else(|e| panic!("{}: {e}", docs.display()));
        loud(&format!(
            "the page looks different: wrote {}",
            docs.display()
        ));
    }
}

/// Whether `new` looks different from the picture in `old`: another size,
/// or more than 1% of its pixels changed. (The times the page shows change
/// from run to run, a few hundred pixels; a change of its look, far more.)
fn looks_different(new: &image::RgbaImage, old: &Path) -> bool {
    let Ok(old) = image::open(old) else {
        return true;
    };
    let old = old.to_rgba8();
    old.dimensions() != new.dimensions() || {
        let changed = old
            .pixels()
            .zip(new.pixels())
            .filter(|(a, b)| a != b)
            .count();
        changed * 100 > old.pixels().len()
    }
}

/// Checks that the `COLOR_0` the page's download carries is glint's JSON
/// answer (`POST /v1/shade` with `vertices`) for the same lighting, `sent`
/// (the `request` part of the bake the page sent) with `material` for the
/// model's material, on the model's positions and normals placed by the
/// test's own matrices: `srgb_to_linear` of each colour channel (the
/// `display` colour space), the alpha as it is, each within half a step of
/// unorm16 (and f32's rounding of sRGB's decoding).
async fn colors_are_the_json_answer(
    glint: &Glint,
    name: &str,
    baked: &[u8],
    sent: &Value,
    material: Value,
) {
    let read = read_glb(baked);
    let node = &read.json["nodes"][0];
    let numbers = |v: &Value, default: &[f64]| -> Vec<f64> {
        v.as_array().map_or_else(
            || default.to_vec(),
            |a| a.iter().map(|x| x.as_f64().unwrap()).collect(),
        )
    };
    let t = numbers(&node["translation"], &[0.0; 3]);
    let r = numbers(&node["rotation"], &[0.0, 0.0, 0.0, 1.0]);
    let s = numbers(&node["scale"], &[1.0; 3]);
    let world = trs(
        [t[0], t[1], t[2]],
        [r[0], r[1], r[2], r[3]],
        [s[0], s[1], s[2]],
    );
    let vec3s = |attribute: &str| -> Vec<[f64; 3]> {
        let accessor = read
            .attribute(0, 0, attribute)
            .unwrap_or_else(|| panic!("{name}: no {attribute}"));
        read.floats(accessor)
            .iter()
            .map(|v| [f64::from(v[0]), f64::from(v[1]), f64::from(v[2])])
            .collect()
    };
    let positions: Vec<[f64; 3]> = vec3s("POSITION")
        .into_iter()
        .map(|p| point(&world, p))
        .collect();
    let normals: Vec<[f64; 3]> = vec3s("NORMAL")
        .into_iter()
        .map(|n| unit(normal(&world, n)))
        .collect();

    let mut shade = sent.clone();
    let fields = shade.as_object_mut().unwrap();
    assert_eq!(
        fields.get("vertices"),
        None,
        "{name}: a bake's request has no vertices"
    );
    fields.remove("materials");
    fields.insert("material".into(), material);
    fields.insert(
        "vertices".into(),
        json!({ "positions": positions, "normals": normals }),
    );
    let colors = shaded(glint, &shade).await;

    let color = read
        .attribute(0, 0, "COLOR_0")
        .unwrap_or_else(|| panic!("{name}: no COLOR_0"));
    let accessor = &read.json["accessors"][color];
    assert_eq!(
        accessor["componentType"], 5123,
        "{name}: unorm16, the default"
    );
    let baked = read.floats(color);
    assert_eq!(baked.len(), colors.len(), "{name}");
    let tolerance = 0.5 / 65535.0 + 1e-6;
    let stored = |colors: &[Vec<f64>]| -> Vec<Vec<f64>> {
        colors
            .iter()
            .map(|rgba| {
                let [r, g, b, a] = [rgba[0], rgba[1], rgba[2], rgba[3]];
                vec![srgb_to_linear(r), srgb_to_linear(g), srgb_to_linear(b), a]
            })
            .collect()
    };
    for (k, (got, want)) in baked.iter().zip(stored(&colors)).enumerate() {
        for c in 0..4 {
            let got = f64::from(got[c]);
            assert!(
                (got - want[c]).abs() <= tolerance,
                "{name} vertex {k} channel {c}: COLOR_0 {got}, the JSON answer {} stored as {}",
                colors[k][c],
                want[c]
            );
        }
    }

    // Seen from elsewhere (GL's eye space, the viewer the model would get
    // without a view), the local viewer moves the highlights: the bake was
    // lit as the page's camera sees the model.
    let view = shade.as_object_mut().unwrap().remove("view");
    assert!(
        view.is_some(),
        "{name}: the bake's request has the page's camera as its view"
    );
    let elsewhere = stored(&shaded(glint, &shade).await);
    let moved = baked
        .iter()
        .zip(&elsewhere)
        .flat_map(|(got, other)| (0..3).map(move |c| (f64::from(got[c]) - other[c]).abs()))
        .fold(0.0, f64::max);
    assert!(
        moved > 100.0 * tolerance,
        "{name}: the view changes the colours by only {moved}"
    );
}

/// glint's JSON answer to `shade`, a `/v1/shade` request with vertices: its colours.
async fn shaded(glint: &Glint, shade: &Value) -> Vec<Vec<f64>> {
    let response = client()
        .post(glint.url("/v1/shade"))
        .json(shade)
        .send()
        .await
        .unwrap();
    assert_eq!(response.status(), 200, "{shade}");
    let answer: Value = response.json().await.unwrap();
    answer["colors"]
        .as_array()
        .unwrap()
        .iter()
        .map(|rgba| {
            rgba.as_array()
                .unwrap()
                .iter()
                .map(|c| c.as_f64().unwrap())
                .collect()
        })
        .collect()
}
