//! Every build of the kernel the CPU runs, forced for a whole process by
//! `GLINT_KERNEL_ISA` (the operator's way to choose one), lights as GL
//! does: the binary's `shade` in each build against the f64 reference tier
//! of the same request, within the documented bound the answer states. A
//! name that is no build, or a build this CPU does not run, stops the
//! process at its start with a line naming the variable.

use glint_lighting::kernel::{ISA_VARIABLE, InstructionSet};
use serde_json::{Value, json};

use crate::support::{Rng, Scratch};

/// 8 spotlights and a local viewer with separate specular (every variant
/// the kernel builds for positional light), at 1,000 random vertices: the
/// kernel's blocks, tasks and tail all take part.
fn request(rng: &mut Rng) -> Value {
    let mut point = |lo: f64, hi: f64| {
        [
            rng.uniform(lo, hi),
            rng.uniform(lo, hi),
            rng.uniform(lo, hi),
        ]
    };
    let lights: Vec<Value> = (0..8)
        .map(|i| {
            let p = point(-3.0, 3.0);
            json!({
                "position": [p[0], p[1], p[2], 1.0],
                "diffuse": [0.6, 0.5, 0.4], "specular": [0.9, 0.9, 0.8], "ambient": [0.05, 0.05, 0.05],
                "attenuation": [1.0, 0.05, 0.01],
                "spot": { "direction": [-p[0], -p[1], -p[2] - 3.0], "cutoff": 30.0 + 5.0 * f64::from(i), "exponent": 4.0 * f64::from(i) }
            })
        })
        .collect();
    let positions: Vec<[f64; 3]> = (0..1000)
        .map(|_| point(-2.0, 2.0))
        .map(|[x, y, z]| [x, y, z - 3.0])
        .collect();
    let normals: Vec<[f64; 3]> = (0..1000).map(|_| point(-1.0, 1.0)).collect();
    json!({
        "light_model": { "local_viewer": true, "color_control": "separate_specular", "two_side": true },
        "material": { "diffuse": [0.8, 0.3, 0.2], "specular": [1, 1, 1], "shininess": 40, "emission": [0.02, 0.0, 0.0] },
        "lights": lights,
        "vertices": { "positions": positions, "normals": normals },
    })
}

fn shade(file: &std::path::Path, isa: Option<&str>) -> std::process::Output {
    let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_glint"));
    command.arg("shade").arg(file).env_remove(ISA_VARIABLE);
    if let Some(isa) = isa {
        command.env(ISA_VARIABLE, isa);
    }
    command.output().unwrap()
}

fn colors(answer: &Value, key: &str) -> Vec<f64> {
    answer[key]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|c| c.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()))
        .collect()
}

#[test]
fn every_build_the_cpu_runs_lights_within_the_tiers_bounds() {
    let dir = Scratch::new("instruction-sets");
    let mut rng = Rng::new(0x15a);
    let mut body = request(&mut rng);
    let file = dir.path().join("request.json");
    body["precision"] = json!("reference");
    std::fs::write(&file, body.to_string()).unwrap();
    let output = shade(&file, None);
    assert!(output.status.success(), "{output:?}");
    let reference: Value = serde_json::from_slice(&output.stdout).unwrap();
    for tier in ["accurate", "fast"] {
        body["precision"] = json!(tier);
        std::fs::write(&file, body.to_string()).unwrap();
        for isa in InstructionSet::here() {
            let output = shade(&file, Some(isa.name()));
            assert!(output.status.success(), "{isa}: {output:?}");
            let answer: Value = serde_json::from_slice(&output.stdout).unwrap();
            assert_eq!(answer["precision"]["mode"], tier);
            let bound = answer["precision"]["max_abs_error"].as_f64().unwrap();
            for side in ["colors", "back_colors"] {
                let (got, want) = (colors(&answer, side), colors(&reference, side));
                assert_eq!(got.len(), want.len());
                let worst = got
                    .iter()
                    .zip(&want)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, f64::max);
                assert!(
                    worst <= bound,
                    "{isa} build, {tier}, {side}: {worst} > {bound}"
                );
            }
        }
    }
}

#[test]
fn a_build_that_is_none_or_that_the_cpu_does_not_run_stops_the_process() {
    let dir = Scratch::new("instruction-sets-refused");
    let file = dir.path().join("request.json");
    std::fs::write(&file, request(&mut Rng::new(1)).to_string()).unwrap();
    let refused: Vec<&str> = ["sse9"]
        .into_iter()
        .chain(
            InstructionSet::ALL
                .into_iter()
                .filter(|isa| !isa.runs_here())
                .map(InstructionSet::name),
        )
        .collect();
    for name in refused {
        let output = shade(&file, Some(name));
        assert_eq!(output.status.code(), Some(1), "{name}: {output:?}");
        assert!(output.stdout.is_empty(), "{name}: no answer");
        let said = String::from_utf8_lossy(&output.stderr);
        assert!(
            said.contains(&format!("{ISA_VARIABLE}={name}")),
            "{name}: {said}"
        );
    }
}
