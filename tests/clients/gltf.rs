//! Baked models in the hands of glTF tools this project did not write: the
//! Khronos glTF validator (`gltf-validator` from npm) reports no error on
//! any of them, and pygltflib (from PyPI) reads their `COLOR_0` back equal
//! to glint's JSON answer for the same request. The playground's browser
//! test checks the models the page downloads with the same validator
//! ([`khronos_reports`]).

use std::fs;
use std::path::PathBuf;
use std::time::Duration;

use glint::bake::{self, Form};
use glint::scene::{Limits, parse_bake};
use serde_json::{Value, json};

use super::{NodePackages, PythonTools, Scratch, available, pins, run};
use crate::gltf::bake::{hierarchy, lit_scene, request};
use crate::gltf::support::srgb_to_linear;

/// A model, the request it is baked with, and what to call it.
struct Bake {
    name: &'static str,
    glb: Vec<u8>,
    request: Option<Value>,
}

/// Models baked in every format and colour space, two-sided and with
/// per-vertex terms, and from the model's own lights, materials and camera.
fn bakes() -> Vec<Bake> {
    let hierarchy = hierarchy().0.glb();
    let with = |changes: Value| {
        let mut r = request();
        for (k, v) in changes.as_object().unwrap() {
            r[k] = v.clone();
        }
        Some(r)
    };
    vec![
        Bake {
            name: "default",
            glb: hierarchy.clone(),
            request: Some(request()),
        },
        Bake {
            name: "unorm8",
            glb: hierarchy.clone(),
            request: with(json!({ "color_format": "unorm8" })),
        },
        Bake {
            name: "float-linear",
            glb: hierarchy.clone(),
            request: with(json!({ "color_format": "float", "color_space": "linear" })),
        },
        Bake {
            name: "two-sided-terms",
            glb: hierarchy,
            request: with(json!({
                "light_model": { "two_side": true, "local_viewer": true },
                "terms": "per_vertex"
            })),
        },
        Bake {
            name: "model-lights",
            glb: lit_scene().0.glb(),
            request: None,
        },
    ]
}

fn baked(bake: &Bake, form: Form) -> Vec<u8> {
    let request = bake
        .request
        .as_ref()
        .map(|r| serde_json::to_vec(r).unwrap());
    let scene = parse_bake(request.as_deref(), &bake.glb, &Limits::default()).unwrap();
    bake::bake(scene, form).body.to_vec(&bake.glb)
}

/// Writes each bake's model (and, with `inputs`, the input model too) into
/// `dir`; returns the files.
fn write(dir: &std::path::Path, bakes: &[Bake], inputs: bool) -> Vec<PathBuf> {
    let mut files = Vec::new();
    for bake in bakes {
        let file = dir.join(format!("{}.glb", bake.name));
        fs::write(&file, baked(bake, Form::Glb)).unwrap();
        files.push(file);
        if inputs {
            let file = dir.join(format!("{}-input.glb", bake.name));
            fs::write(&file, &bake.glb).unwrap();
            files.push(file);
        }
    }
    files
}

/// The Khronos validator's report of each of `files`, keyed by its path:
/// its counts of `errors` and `warnings`, and its error `messages`. `None`
/// after saying loudly why the validator is not there, for `test` (in CI,
/// a panic instead).
pub(crate) async fn khronos_reports(files: &[PathBuf], test: &str) -> Option<Value> {
    let node = available(NodePackages::pinned_by("clients").await, test)?;
    let validator = node.script("gltf-validator", "");
    let script = pins().join("gltf_validate.js");
    let mut args = vec![script.as_os_str(), validator.as_os_str()];
    args.extend(files.iter().map(|f| f.as_os_str()));
    let output = run("node", &args, |_| {}, Duration::from_secs(120))
        .await
        .unwrap_or_else(|e| panic!("{e}"));
    Some(serde_json::from_slice(&output.stdout).unwrap())
}

#[tokio::test]
async fn the_khronos_validator_finds_no_error_in_a_baked_model() {
    let test = "the_khronos_validator_finds_no_error_in_a_baked_model";
    let work = Scratch::new("gltf-validator");
    let bakes = bakes();
    // The inputs too: a baked model's errors are then glint's own.
    let files = write(work.path(), &bakes, true);
    let Some(reports) = khronos_reports(&files, test).await else {
        return;
    };
    for file in &files {
        let report = &reports[file.to_str().unwrap()];
        assert_eq!(report["errors"], 0, "{}: {report}", file.display());
    }
}

#[tokio::test]
async fn a_python_reader_reads_the_colors_of_the_json_answer() {
    let test = "a_python_reader_reads_the_colors_of_the_json_answer";
    let Some(python) = available(PythonTools::pinned_by("clients").await, test) else {
        return;
    };
    let work = Scratch::new("gltf-python");
    let bakes = bakes();
    let files = write(work.path(), &bakes, false);
    let script = pins().join("gltf_colors.py");
    let mut args = vec![script.as_os_str()];
    args.extend(files.iter().map(|f| f.as_os_str()));
    let output = run(
        python.bin("python"),
        &args,
        |_| {},
        Duration::from_secs(120),
    )
    .await
    .unwrap_or_else(|e| panic!("{e}"));
    let read: Value = serde_json::from_slice(&output.stdout).unwrap();
    for (bake, file) in bakes.iter().zip(&files) {
        let answer: Value = serde_json::from_slice(&baked(bake, Form::Json)).unwrap();
        let request = bake.request.clone().unwrap_or_default();
        let linear = request["color_space"] == "linear";
        // Half a step of the stored format, and f32's rounding of sRGB's
        // decoding.
        let step = match request["color_format"].as_str() {
            Some("float") => 0.0,
            Some("unorm8") => 1.0 / 255.0,
            _ => 1.0 / 65535.0,
        };
        let tolerance = step / 2.0 + if linear { 0.0 } else { 1e-6 };
        // The reader lists nodes in index order, glint's runs follow the
        // scene depth first.
        let runs = read[file.to_str().unwrap()].as_array().unwrap();
        let primitives = answer["primitives"].as_array().unwrap();
        assert_eq!(runs.len(), primitives.len(), "{}", bake.name);
        for primitive in primitives {
            let run = runs
                .iter()
                .find(|r| {
                    r["node"] == primitive["node"] && r["primitive"] == primitive["primitive"]
                })
                .unwrap_or_else(|| panic!("{}: no COLOR_0 for {primitive}", bake.name));
            let first = primitive["first"].as_u64().unwrap() as usize;
            for (k, color) in run["colors"].as_array().unwrap().iter().enumerate() {
                let want = &answer["colors"][first + k];
                for c in 0..4 {
                    let got = color[c].as_f64().unwrap();
                    let gl = want[c].as_f64().unwrap();
                    let stored = if linear || c == 3 {
                        gl
                    } else {
                        srgb_to_linear(gl)
                    };
                    if step == 0.0 {
                        // Floats: the very numbers of the JSON answer.
                        assert_eq!(got as f32, stored as f32, "{}", bake.name);
                    } else {
                        assert!(
                            (got - stored).abs() <= tolerance,
                            "{} vertex {k}: {got} against {stored}",
                            bake.name
                        );
                    }
                }
            }
        }
    }
}
