//! `glint compare REQUEST CANDIDATE`: the summary, and an exit code a port's
//! test suite can use (0 within the bound, 1 outside it, 2 for a bad
//! request).

use std::process::Command;

use super::every_term;
use crate::support::Scratch;

/// `glint compare` of the scene's request and a candidate of a port with
/// `deviations`, or of `candidate` where given, in the scratch directory
/// `name`: its exit code and stdout.
fn glint_compare(name: &str, deviations: &[&str], candidate: Option<&str>) -> (i32, String) {
    let scratch = Scratch::new(name);
    let scene = every_term();
    let request = scratch.path().join("request.json");
    let candidate_file = scratch.path().join("candidate.json");
    std::fs::write(&request, scene.request("reference").to_string()).unwrap();
    let candidate = candidate
        .map(str::to_owned)
        .unwrap_or_else(|| scene.candidate(deviations).to_string());
    std::fs::write(&candidate_file, candidate).unwrap();
    let output = Command::new(env!("CARGO_BIN_EXE_glint"))
        .arg("compare")
        .arg(&request)
        .arg(&candidate_file)
        .output()
        .unwrap();
    (
        output.status.code().unwrap(),
        String::from_utf8(output.stdout).unwrap(),
    )
}

#[test]
fn gl_s_colours_exit_0() {
    let (code, out) = glint_compare("compare-cli-gl", &[], None);
    assert_eq!(code, 0, "{out}");
    assert!(out.contains("within the bound"), "{out}");
}

#[test]
fn a_port_s_colours_exit_1_and_name_its_deviation_first() {
    let (code, out) = glint_compare("compare-cli-port", &["phong_specular"], None);
    assert_eq!(code, 1, "{out}");
    let first = out.lines().nth(1).unwrap();
    assert!(
        first.starts_with('*') && first.contains("phong_specular"),
        "{out}"
    );
}

#[test]
fn a_bad_candidate_exits_2() {
    let (code, _) = glint_compare(
        "compare-cli-bad",
        &[],
        Some(r#"{"colors": [[0, 0, 0, 1]]}"#),
    );
    assert_eq!(code, 2);
}
