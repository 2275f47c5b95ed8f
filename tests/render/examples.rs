//! The example scenes of `examples/` render, and their images are written
//! to `target/render-examples/` for a person to look at.

use serde_json::Value;

use super::support::{decode_png, json_of, scene_of};
use crate::support::repo;

fn example(name: &str) -> Value {
    let path = repo().join("examples").join(name);
    let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_slice(&bytes).unwrap()
}

#[test]
fn example_scenes_render_to_target_render_examples() {
    let out = repo().join("target/render-examples");
    std::fs::create_dir_all(&out).unwrap();
    for (name, triangles) in [("spheres", 0), ("mesh", 1984)] {
        let request = example(&format!("{name}.json"));
        let scene = scene_of(&request);
        let png = glint::render::render_png(&scene);
        std::fs::write(out.join(format!("{name}.png")), &png).unwrap();

        let img = decode_png(&png);
        assert_eq!(img.dimensions(), (scene.camera.width, scene.camera.height));
        assert_eq!(scene.triangles(), triangles);
        // Most pixels see an object, in many colours.
        let background = glint_trace::film::encode(scene.background, scene.encoding);
        let hit = img.pixels().filter(|p| p.0 != background).count();
        assert!(
            hit * 2 > img.pixels().len(),
            "{name}: only {hit} pixels hit"
        );
        let colours: std::collections::HashSet<_> = img.pixels().collect();
        assert!(colours.len() > 1000, "{name}: {} colours", colours.len());
    }
}

#[test]
fn example_scenes_have_sensible_json_forms() {
    let body = json_of(&example("mesh.json"));
    assert_eq!(body["stats"]["triangles"], 1984);
    assert_eq!(body["warnings"][0]["code"], "per_pixel_fallback");
    assert_eq!(body["warnings"][0]["count"], 1);
    let modeled: Vec<&str> = body["modeled"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert!(modeled.contains(&"lights[0].attenuation"));
    assert!(modeled.contains(&"lights[1].specular"));
    assert!(!modeled.contains(&"emission"));
    let summary = &body["terms"]["summary"];
    assert!(summary["vertices"].as_u64().unwrap() > 100_000);
    assert_eq!(summary["lights"].as_array().unwrap().len(), 2);
}
