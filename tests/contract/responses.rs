//! Real answers of the code against the schemas the document names for
//! them, and against what the document says of their parts: `/v1/shade`
//! bodies (`ShadeResponse`) in every combination of sides, terms and
//! precision; `/v1/render` JSON bodies (`RenderJsonResponse`) in every
//! shading mode and precision, with and without samples, shadows, two
//! sides, a region and anything hit; baked models (`ShadeResponse` with
//! `primitives`, and a GLB's `extras.glint`); and the problems of refused
//! requests (`Problem`, pointing into the body).

use std::sync::LazyLock;

use base64::Engine;
use glint::scene::{self, Limits};
use serde_json::{Value, json};

use super::support::{
    assert_each_valid, assert_problem_points_into, assert_valid, document, quad_beside_a_sphere,
    schema, sphere_on_a_floor, sphere_on_a_floor_but, validator_in,
};

/// One real `/v1/shade` answer and what was asked of it.
struct ShadeAnswer {
    two_side: bool,
    terms: &'static str,
    precision: &'static str,
    /// No vertices.
    empty: bool,
    /// The bound of the precision the scene was read with.
    bound: f64,
    out: Value,
}

/// Every combination of sides, terms, precision and vertices or none, two
/// lights (one a positional spotlight), a global ambient over 1 and a
/// negative emission; among the vertices a zero normal and one facing away.
static SHADE_ANSWERS: LazyLock<Vec<ShadeAnswer>> = LazyLock::new(|| {
    let lights = json!([
        { "position": [0, 1, 1, 0], "specular": [1, 1, 1] },
        { "position": [0, 2, 3, 1], "attenuation": [1, 0.5, 0.25],
          "spot": { "direction": [0, -1, -1], "cutoff": 60, "exponent": 4 } },
    ]);
    let vertices = json!({
        "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [5, 5, 5]],
        "normals": [[0, 0, 1], [0, 0, -1], [0, 0, 0], [1, 1, 1]],
    });
    let mut answers = Vec::new();
    for two_side in [false, true] {
        for terms in ["none", "summary", "per_vertex"] {
            for precision in ["reference", "accurate", "fast"] {
                for empty in [false, true] {
                    let vertices = if empty {
                        json!({ "positions": [], "normals": [] })
                    } else {
                        vertices.clone()
                    };
                    let body = json!({
                        "light_model": { "two_side": two_side, "ambient": [3, 3, 3] },
                        "material": { "specular": [0.5, 0.5, 0.5], "shininess": 10,
                                      "emission": [-0.5, 0, 0] },
                        "lights": lights,
                        "vertices": vertices,
                        "precision": precision,
                        "terms": terms,
                    });
                    let scene =
                        scene::parse_shade(&serde_json::to_vec(&body).unwrap(), &Limits::default())
                            .unwrap_or_else(|e| panic!("{body}: {e}"));
                    answers.push(ShadeAnswer {
                        two_side,
                        terms,
                        precision,
                        empty,
                        bound: scene.precision.max_abs_error(),
                        out: serde_json::to_value(glint::shade::shade(&scene)).unwrap(),
                    });
                }
            }
        }
    }
    answers
});

#[test]
fn every_shade_answer_is_a_shade_response() {
    assert_each_valid("ShadeResponse", SHADE_ANSWERS.iter().map(|a| &a.out));
}

/// The bound is the one its mode documents.
#[test]
fn a_shade_answer_states_its_mode_and_bound() {
    for answer in SHADE_ANSWERS.iter() {
        let out = &answer.out;
        assert_eq!(out["precision"]["mode"], answer.precision);
        assert_eq!(
            out["precision"]["max_abs_error"].as_f64(),
            Some(answer.bound),
            "{out}"
        );
    }
}

#[test]
fn back_colors_come_with_two_sides_only() {
    for answer in SHADE_ANSWERS.iter() {
        let out = &answer.out;
        assert_eq!(out.get("back_colors").is_some(), answer.two_side, "{out}");
    }
}

#[test]
fn terms_come_unless_none_are_asked() {
    for answer in SHADE_ANSWERS.iter() {
        let out = &answer.out;
        assert_eq!(out.get("terms").is_some(), answer.terms != "none", "{out}");
    }
}

/// In every answer with terms, the part `part` of its terms is there
/// exactly when `expected` says.
#[track_caller]
fn assert_terms_part(part: &str, expected: impl Fn(&ShadeAnswer) -> bool) {
    for answer in SHADE_ANSWERS.iter().filter(|a| a.terms != "none") {
        let out = &answer.out;
        assert_eq!(out["terms"].get(part).is_some(), expected(answer), "{out}");
    }
}

#[test]
fn a_terms_summary_comes_unless_there_are_no_vertices() {
    assert_terms_part("summary", |answer| !answer.empty);
}

#[test]
fn per_vertex_terms_come_only_when_asked() {
    assert_terms_part("per_vertex", |answer| answer.terms == "per_vertex");
}

#[test]
fn back_terms_come_with_two_sides_only() {
    assert_terms_part("back", |answer| answer.two_side);
}

/// The problems of refused shades validate against `Problem`, and each
/// points at a place in the body, or the whole body.
#[test]
fn a_refused_shade_s_problem_points_into_its_body() {
    let doc = document();
    let refused = [
        json!({}),
        json!({ "vertices": { "positions": [], "normals": [] }, "lights": [{ "spot": { "cutoff": 120 } }] }),
        json!({ "vertices": { "positions": [[0, 0, 0]], "normals": [] } }),
        json!({ "vertices": { "positions": [], "normals": [] }, "lights": (0..65).map(|_| json!({})).collect::<Vec<_>>() }),
    ];
    for body in refused {
        let e = scene::parse_shade(&serde_json::to_vec(&body).unwrap(), &Limits::default())
            .expect_err("refused");
        assert_problem_points_into(&doc, &e, &body);
    }
}

/// What a render asks besides its shading and precision.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Variant {
    /// The scene as it is.
    Plain,
    /// 4 samples, shadows, two sides, a back material, a 17×9 region and
    /// sRGB.
    Everything,
    /// Nothing to hit: no summary, every probe a miss.
    Empty,
}

/// One real `/v1/render` JSON answer and what was asked of it.
struct RenderAnswer {
    shading: &'static str,
    variant: Variant,
    body: Value,
    out: Value,
}

/// [`sphere_on_a_floor`] shaded per pixel and [`quad_beside_a_sphere`] per
/// vertex, in each precision and each [`Variant`].
static RENDER_ANSWERS: LazyLock<Vec<RenderAnswer>> = LazyLock::new(|| {
    let mut answers = Vec::new();
    for shading in ["per_pixel", "per_vertex"] {
        for precision in ["reference", "accurate", "fast"] {
            for variant in [Variant::Plain, Variant::Everything, Variant::Empty] {
                let mut body = if shading == "per_vertex" {
                    quad_beside_a_sphere()
                } else {
                    sphere_on_a_floor()
                };
                body["shading"] = json!(shading);
                body["precision"] = json!(precision);
                if variant == Variant::Everything {
                    body["samples"] = json!(4);
                    body["shadows"] = json!(true);
                    body["light_model"] = json!({ "two_side": true });
                    body["back_material"] = json!({ "diffuse": [0, 1, 0] });
                    body["region"] = json!({ "x": 8, "y": 4, "width": 17, "height": 9 });
                    body["encoding"] = json!("srgb");
                }
                if variant == Variant::Empty {
                    body["objects"] = json!([]);
                }
                let scene =
                    scene::parse_render(&serde_json::to_vec(&body).unwrap(), &Limits::default())
                        .unwrap_or_else(|e| panic!("{body}: {e}"));
                let out = glint::render::render_json(&scene, &|| false).expect("not cancelled");
                answers.push(RenderAnswer {
                    shading,
                    variant,
                    body,
                    out: serde_json::to_value(out).unwrap(),
                });
            }
        }
    }
    answers
});

/// The probes of an answer, beside the pixels the request named.
fn probes(answer: &RenderAnswer) -> (&Vec<Value>, &Vec<Value>) {
    (
        answer.out["terms"]["probes"].as_array().unwrap(),
        answer.body["probes"].as_array().unwrap(),
    )
}

#[test]
fn every_render_json_is_a_render_json_response() {
    assert_each_valid("RenderJsonResponse", RENDER_ANSWERS.iter().map(|a| &a.out));
}

/// Every key of the answer and of its parts is a property of its schema.
#[test]
fn a_render_json_says_nothing_it_does_not_document() {
    let doc = document();
    let schemas = &doc["components"]["schemas"];
    let documented = |schema: &str, value: &Value| {
        for key in value.as_object().expect("an object").keys() {
            assert!(
                schemas[schema]["properties"].get(key).is_some(),
                "{schema} does not document `{key}`: {value}"
            );
        }
    };
    for answer in RENDER_ANSWERS.iter() {
        let out = &answer.out;
        documented("RenderJsonResponse", out);
        documented("RenderStats", &out["stats"]);
        documented("RenderTerms", &out["terms"]);
        for probe in probes(answer).0 {
            documented("Probe", probe);
            if !probe["hit"].is_null() {
                documented("ProbeHit", &probe["hit"]);
            }
        }
    }
}

/// The image is the region's size (the whole image without one), and so
/// are its stats.
#[test]
fn a_render_json_is_the_size_of_its_region() {
    for answer in RENDER_ANSWERS.iter() {
        let out = &answer.out;
        let (width, height) = if answer.variant == Variant::Everything {
            (17, 9)
        } else {
            (32, 24)
        };
        assert_eq!(
            (out["width"].as_u64(), out["height"].as_u64()),
            (Some(width), Some(height))
        );
        let stats = &out["stats"];
        assert_eq!(
            (
                stats["width"].as_u64(),
                stats["height"].as_u64(),
                stats["pixels"].as_u64()
            ),
            (Some(width), Some(height), Some(width * height))
        );
    }
}

#[test]
fn png_base64_holds_a_png() {
    for answer in RENDER_ANSWERS.iter() {
        let png = base64::engine::general_purpose::STANDARD
            .decode(answer.out["png_base64"].as_str().unwrap())
            .expect("png_base64 is base64");
        assert!(png.starts_with(b"\x89PNG\r\n\x1a\n"), "not a PNG");
    }
}

#[test]
fn a_render_s_terms_summary_comes_unless_nothing_is_hit() {
    for answer in RENDER_ANSWERS.iter() {
        let out = &answer.out;
        assert_eq!(
            out["terms"].get("summary").is_some(),
            answer.variant != Variant::Empty,
            "{out}"
        );
    }
}

#[test]
fn each_probe_answers_its_pixel() {
    for answer in RENDER_ANSWERS.iter() {
        let (probes, pixels) = probes(answer);
        assert_eq!(probes.len(), pixels.len());
        for (probe, pixel) in probes.iter().zip(pixels) {
            assert_eq!(&probe["pixel"], pixel);
        }
    }
}

/// As `Probe` says: a miss has neither, a hit has both.
#[test]
fn a_probe_has_a_hit_and_a_breakdown_or_neither() {
    for answer in RENDER_ANSWERS.iter() {
        for probe in probes(answer).0 {
            assert_eq!(
                probe["hit"].is_null(),
                probe["breakdown"].is_null(),
                "{probe}"
            );
        }
    }
}

/// The last probe of each scene is on the background.
#[test]
fn a_probe_on_the_background_misses() {
    for answer in RENDER_ANSWERS.iter() {
        let miss = probes(answer).0.last().unwrap();
        assert!(
            miss["hit"].is_null() && miss["breakdown"].is_null(),
            "{miss}"
        );
    }
}

/// The first probe of each scene is on an object's front.
#[test]
fn a_probe_on_an_object_hits_its_front() {
    for answer in RENDER_ANSWERS
        .iter()
        .filter(|a| a.variant != Variant::Empty)
    {
        let out = &answer.out;
        let first = &probes(answer).0[0];
        assert_eq!(first["hit"]["side"], "front", "{out}");
        assert!(first["breakdown"].is_object(), "{out}");
    }
}

/// Per-vertex shading warns that it shades the sphere per pixel and that
/// the quad has a zero normal; nothing else warns.
#[test]
fn render_warnings_are_those_of_per_vertex_shading() {
    for answer in RENDER_ANSWERS.iter() {
        let out = &answer.out;
        let codes: Vec<&str> = out["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .map(|w| w["code"].as_str().unwrap())
            .collect();
        let expected: &[&str] = match (answer.shading, answer.variant) {
            ("per_vertex", Variant::Plain | Variant::Everything) => {
                &["per_pixel_fallback", "zero_normals"]
            }
            _ => &[],
        };
        assert_eq!(codes, expected, "{out}");
    }
}

/// The problems of refused renders validate against `Problem`, and each
/// points at a place in the body, or the whole body.
#[test]
fn a_refused_render_s_problem_points_into_its_body() {
    let doc = document();
    let refused = [
        json!({}),
        sphere_on_a_floor_but(&|b| b["lights"] = json!([{ "spot": { "cutoff": 120 } }])),
        sphere_on_a_floor_but(&|b| b["samples"] = json!(0)),
        sphere_on_a_floor_but(&|b| {
            b["camera"]["width"] = json!(4000);
            b["camera"]["height"] = json!(4000);
        }),
        sphere_on_a_floor_but(&|b| b["probes"] = json!([[32, 0]])),
    ];
    for body in refused {
        let e = scene::parse_render(&serde_json::to_vec(&body).unwrap(), &Limits::default())
            .expect_err("refused");
        assert_problem_points_into(&doc, &e, &body);
    }
}

/// One bake of the glTF tests' model, as JSON and as a GLB, and the
/// request that asked for it.
struct ModelAnswer {
    terms: &'static str,
    request: Value,
    json: Value,
    /// The GLB's `extras.glint`.
    extras: Value,
}

/// The glTF tests' hierarchy baked with one side and two, with each detail
/// of terms.
static MODEL_ANSWERS: LazyLock<Vec<ModelAnswer>> = LazyLock::new(|| {
    use glint::bake::{self, Form};
    let (model, _) = crate::gltf::bake::hierarchy();
    let glb = model.glb();
    let mut answers = Vec::new();
    for two_side in [false, true] {
        for terms in ["none", "summary", "per_vertex"] {
            let mut request = crate::gltf::bake::request();
            request["light_model"]["two_side"] = json!(two_side);
            request["terms"] = json!(terms);
            let body = serde_json::to_vec(&request).unwrap();
            let baked = |form| {
                let scene = scene::parse_bake(Some(&body), &glb, &Limits::default()).unwrap();
                bake::bake(scene, form).body.to_vec(&glb)
            };
            let json: Value = serde_json::from_slice(&baked(Form::Json)).unwrap();
            let extras =
                crate::gltf::support::read_glb(&baked(Form::Glb)).json["extras"]["glint"].clone();
            answers.push(ModelAnswer {
                terms,
                request,
                json,
                extras,
            });
        }
    }
    answers
});

/// The requests of the glTF tests are `ModelShadeRequest`s.
#[test]
fn a_model_shade_request_is_a_model_shade_request() {
    assert_each_valid(
        "ModelShadeRequest",
        MODEL_ANSWERS.iter().map(|a| &a.request),
    );
}

/// The JSON answers of `/v1/shade` with a model are `ShadeResponse`s with
/// `primitives`.
#[test]
fn a_baked_json_answer_is_a_shade_response_with_primitives() {
    assert_each_valid("ShadeResponse", MODEL_ANSWERS.iter().map(|a| &a.json));
    for answer in MODEL_ANSWERS.iter() {
        assert!(
            answer.json["primitives"]
                .as_array()
                .is_some_and(|p| !p.is_empty())
        );
    }
}

/// A baked GLB's `extras.glint` holds what the contract says: its `stats`
/// a `ShadeStats`, its warnings `Warning`s, what it modeled, its precision,
/// and a summary when terms are asked.
#[test]
fn a_baked_glb_holds_the_contract_s_extras() {
    let doc = document();
    let stats = validator_in(&doc, "ShadeStats");
    let warning = validator_in(&doc, "Warning");
    for answer in MODEL_ANSWERS.iter() {
        let glint = &answer.extras;
        assert_valid(&stats, "ShadeStats", &glint["stats"]);
        for w in glint["warnings"].as_array().unwrap() {
            assert_valid(&warning, "Warning", w);
        }
        assert!(glint["modeled"].is_array() && glint["precision"].is_object());
        assert_eq!(glint.get("summary").is_some(), answer.terms != "none");
    }
}

/// Every property of the schema is a field of the wire type: an object of
/// all of them parses.
#[test]
fn the_model_request_s_properties_are_the_wire_type_s_fields() {
    let request = schema("ModelShadeRequest");
    let properties = request["properties"].as_object().unwrap();
    let mut all = crate::gltf::bake::request();
    all["back_material"] = json!({});
    all["precision"] = json!("fast");
    all["terms"] = json!("summary");
    all["color_space"] = json!("linear");
    all["color_format"] = json!("unorm8");
    let keys: Vec<&String> = all.as_object().unwrap().keys().collect();
    let mut names: Vec<&String> = properties.keys().collect();
    names.sort();
    let mut sorted = keys.clone();
    sorted.sort();
    assert_eq!(sorted, names);
    let body = serde_json::to_vec(&all).unwrap();
    let (model, _) = crate::gltf::bake::hierarchy();
    scene::parse_bake(Some(&body), &model.glb(), &Limits::default()).unwrap();
}
