//! Baked colours against the f64 reference on geometry the test places
//! itself, and the shape of the baked model.

use glam::{DVec3, DVec4};
use glint::bake::{self, Form};
use glint::scene::{Limits, parse_bake};
use glint_lighting::{
    Light, LightModel, LightPosition, LightSet, Material, Side, Spot, SurfaceMaterial, Viewer,
    reference,
};
use serde_json::{Value, json};

use super::support::*;

/// The tent: a square base and an apex, four triangles.
pub const TENT: [[f32; 3]; 5] = [
    [-1.0, 0.0, -1.0],
    [1.0, 0.0, -1.0],
    [1.0, 0.0, 1.0],
    [-1.0, 0.0, 1.0],
    [0.0, 1.0, 0.0],
];
pub const TENT_INDICES: [u32; 12] = [0, 4, 1, 1, 4, 2, 2, 4, 3, 3, 4, 0];

/// Unit normals (as glTF asks), leaning out of the tent.
fn tent_normals() -> Vec<[f32; 3]> {
    TENT.iter()
        .map(|p| {
            unit([
                f64::from(p[0]) * 2.0,
                f64::from(p[1]) + 0.5,
                f64::from(p[2]) * 2.0,
            ])
            .map(|x| x as f32)
        })
        .collect()
}

/// Two triangles side by side.
const QUAD: [[f32; 3]; 6] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [1.0, 0.0, 0.0],
    [1.0, 1.0, 0.2],
    [0.0, 1.0, 0.0],
];

/// A node's placement as the test computes it.
pub struct Expected {
    pub node: usize,
    pub primitive: usize,
    pub world: M4,
    pub positions: Vec<[f64; 3]>,
    /// `None`: computed from the triangles.
    pub normals: Option<Vec<[f64; 3]>>,
    pub triangles: Vec<[usize; 3]>,
    pub material: &'static str,
}

impl Expected {
    /// Positions and unit normals in world space, by the test's matrices.
    pub fn placed(&self) -> Vec<([f64; 3], [f64; 3])> {
        let positions: Vec<[f64; 3]> = self
            .positions
            .iter()
            .map(|&p| point(&self.world, p))
            .collect();
        let normals: Vec<[f64; 3]> = match &self.normals {
            Some(normals) => normals
                .iter()
                .map(|&n| unit(normal(&self.world, n)))
                .collect(),
            None => {
                // Area weighted, each triangle wound counter-clockwise in
                // world space: reversed where the matrix mirrors.
                let mut sums = vec![[0.0; 3]; positions.len()];
                for &[a, b, c] in &self.triangles {
                    let (b, c) = if determinant(&self.world) < 0.0 {
                        (c, b)
                    } else {
                        (b, c)
                    };
                    let n = cross(
                        sub(positions[b], positions[a]),
                        sub(positions[c], positions[a]),
                    );
                    for i in [a, b, c] {
                        for k in 0..3 {
                            sums[i][k] += n[k];
                        }
                    }
                }
                sums.into_iter().map(unit).collect()
            }
        };
        positions.into_iter().zip(normals).collect()
    }
}

/// A model of a node hierarchy (rotation, non-uniform and negative scale,
/// a matrix), a mesh used by two nodes, and a mesh of two primitives with
/// two materials (interleaved and indexed by bytes; sparse, non-indexed and
/// without normals), with what the test expects of each placed primitive.
pub fn hierarchy() -> (Gltf, Vec<Expected>) {
    let mut g = Gltf::new();
    let tent_positions = g.vec3s(&TENT);
    let tent_normals_accessor = g.vec3s(&tent_normals());
    let tent_indices = g.indices(&TENT_INDICES, 5123);
    let tent = g.mesh(json!([{
        "attributes": { "POSITION": tent_positions, "NORMAL": tent_normals_accessor },
        "indices": tent_indices
    }]));
    let quad_normals: Vec<[f32; 3]> = QUAD
        .iter()
        .map(|p| unit([f64::from(p[0]) - 0.5, 0.3, 1.0]).map(|x| x as f32))
        .collect();
    let (quad_p, quad_n) = g.interleaved(&QUAD, &quad_normals);
    let quad_indices = g.indices(&[0, 1, 2, 3, 4, 5], 5121);
    let moved = [(1, [1.5f32, 0.2, 0.1]), (4, [1.2, 1.4, -0.3])];
    let sparse = g.sparse_vec3s(QUAD.len(), Some(&QUAD), &moved);
    let red = g.material(
        json!({ "name": "red", "pbrMetallicRoughness": { "baseColorFactor": [1, 0, 0, 1] } }),
    );
    let blue = g.material(json!({ "pbrMetallicRoughness": { "baseColorFactor": [0, 0, 1, 1] } }));
    let pair = g.mesh(json!([
        { "attributes": { "POSITION": quad_p, "NORMAL": quad_n }, "indices": quad_indices, "material": red },
        { "attributes": { "POSITION": sparse }, "material": blue }
    ]));
    let half = (25f64).to_radians();
    let axis = unit([1.0, 1.0, 0.0]);
    let rotation = [
        axis[0] * half.sin(),
        axis[1] * half.sin(),
        axis[2] * half.sin(),
        half.cos(),
    ];
    let root_trs = ([1.0, 2.0, -3.0], rotation, [2.0, 0.5, 1.5]);
    let mirror_trs = ([0.5, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0], [-1.0, 1.0, 1.0]);
    let (c, s) = ((30f64).to_radians().cos(), (30f64).to_radians().sin());
    // Rotation about z by 30°, scale (1, 3, 1), then a translation.
    let matrix = [
        c,
        s,
        0.0,
        0.0,
        -3.0 * s,
        3.0 * c,
        0.0,
        0.0,
        0.0,
        0.0,
        1.0,
        0.0,
        -2.0,
        0.5,
        1.0,
        1.0,
    ];
    let child_trs = (
        [0.0, 1.0, 0.5],
        [0.0, (0.3f64).sin(), 0.0, (0.3f64).cos()],
        [1.0, 2.0, 0.7],
    );

    let grandchild = g.node(json!({
        "mesh": pair, "translation": child_trs.0, "rotation": child_trs.1, "scale": child_trs.2
    }));
    let mirrored = g.node(json!({
        "mesh": tent, "translation": mirror_trs.0, "scale": mirror_trs.2, "children": [grandchild]
    }));
    let matrixed = g.node(json!({ "mesh": tent, "matrix": matrix }));
    let root = g.node(json!({
        "translation": root_trs.0, "rotation": root_trs.1, "scale": root_trs.2,
        "children": [mirrored, matrixed]
    }));
    g.scene(&[root]);

    let root_m = trs(root_trs.0, root_trs.1, root_trs.2);
    let mirror_m = mul(&root_m, &trs(mirror_trs.0, mirror_trs.1, mirror_trs.2));
    let matrix_m = mul(&root_m, &from_columns(&matrix));
    let child_m = mul(&mirror_m, &trs(child_trs.0, child_trs.1, child_trs.2));
    let f64s = |v: &[[f32; 3]]| v.iter().map(|p| p.map(f64::from)).collect::<Vec<_>>();
    let triangles = |i: &[u32]| {
        i.chunks(3)
            .map(|t| [t[0] as usize, t[1] as usize, t[2] as usize])
            .collect()
    };
    let mut moved_quad = QUAD;
    for (i, v) in moved {
        moved_quad[usize::from(i)] = v;
    }
    let tent_expected = |node, world| Expected {
        node,
        primitive: 0,
        world,
        positions: f64s(&TENT),
        normals: Some(f64s(&tent_normals())),
        triangles: triangles(&TENT_INDICES),
        material: "default",
    };
    // Scene order: depth first, children in order.
    let expected = vec![
        tent_expected(mirrored, mirror_m),
        Expected {
            node: grandchild,
            primitive: 0,
            world: child_m,
            positions: f64s(&QUAD),
            normals: Some(f64s(&quad_normals)),
            triangles: triangles(&[0, 1, 2, 3, 4, 5]),
            material: "red",
        },
        Expected {
            node: grandchild,
            primitive: 1,
            world: child_m,
            positions: f64s(&moved_quad),
            normals: None,
            triangles: triangles(&[0, 1, 2, 3, 4, 5]),
            material: "#1",
        },
        tent_expected(matrixed, matrix_m),
    ];
    (g, expected)
}

/// The request of the bake tests: two lights (one positional with
/// attenuation and a cone), a local viewer, a default material and two
/// named ones.
pub fn request() -> Value {
    json!({
        "light_model": { "local_viewer": true },
        "lights": [
            { "position": [0.3, 1.0, 0.5, 0.0], "diffuse": [0.6, 0.6, 0.6] },
            { "position": [2.0, 3.0, 4.0, 1.0], "diffuse": [0.9, 0.8, 0.7],
              "attenuation": [1.0, 0.1, 0.01],
              "spot": { "direction": [-0.4, -0.5, -1.0], "cutoff": 70, "exponent": 2 } }
        ],
        "view": { "eye": [0.0, 2.0, 8.0], "target": [0.0, 0.0, 0.0] },
        "material": { "diffuse": [0.7, 0.7, 0.2], "specular": [0.5, 0.5, 0.5], "shininess": 20 },
        "materials": {
            "red": { "diffuse": [0.9, 0.1, 0.1], "specular": [1, 1, 1], "shininess": 40 },
            "#1": { "diffuse": [0.1, 0.3, 0.9], "emission": [0.05, 0.0, 0.0] }
        }
    })
}

/// [`request`]'s lights and materials, built by hand.
pub fn request_lighting(two_side: bool) -> (LightSet, impl Fn(&str) -> SurfaceMaterial) {
    let lights = vec![
        Light {
            position: LightPosition::Directional(DVec3::new(0.3, 1.0, 0.5).normalize()),
            diffuse: DVec4::new(0.6, 0.6, 0.6, 1.0),
            ..Light::default()
        },
        Light {
            position: LightPosition::Positional(DVec3::new(2.0, 3.0, 4.0)),
            diffuse: DVec4::new(0.9, 0.8, 0.7, 1.0),
            attenuation: [1.0, 0.1, 0.01],
            spot: Spot {
                direction: DVec3::new(-0.4, -0.5, -1.0).normalize(),
                exponent: 2.0,
                cutoff: 70.0,
            },
            ..Light::default()
        },
    ];
    let model = LightModel {
        local_viewer: true,
        two_side,
        ..LightModel::default()
    };
    let set = LightSet::new(model, lights, Viewer::Local(DVec3::new(0.0, 2.0, 8.0))).unwrap();
    let material = |name: &str| {
        let m = match name {
            "red" => Material {
                diffuse: DVec4::new(0.9, 0.1, 0.1, 1.0),
                specular: DVec4::ONE,
                shininess: 40.0,
                ..Material::default()
            },
            "#1" => Material {
                diffuse: DVec4::new(0.1, 0.3, 0.9, 1.0),
                emission: DVec4::new(0.05, 0.0, 0.0, 1.0),
                ..Material::default()
            },
            _ => Material {
                diffuse: DVec4::new(0.7, 0.7, 0.2, 1.0),
                specular: DVec4::new(0.5, 0.5, 0.5, 1.0),
                shininess: 20.0,
                ..Material::default()
            },
        };
        SurfaceMaterial::both_sides(m)
    };
    (set, material)
}

/// Bakes `glb` with `request` in `form`.
pub fn bake(glb: &[u8], request: &Value, form: Form) -> Vec<u8> {
    let request = serde_json::to_vec(request).unwrap();
    let scene = parse_bake(Some(&request), glb, &Limits::default()).unwrap();
    bake::bake(scene, form).body.to_vec(glb)
}

/// The reference colour of every expected vertex, side by side.
fn reference_colors(expected: &[Expected], two_side: bool, side: Side) -> Vec<Vec<DVec4>> {
    let (lights, material) = request_lighting(two_side);
    expected
        .iter()
        .map(|e| {
            e.placed()
                .into_iter()
                .map(|(p, n)| {
                    reference::color(
                        &lights,
                        &material(e.material),
                        side,
                        DVec3::from_array(p),
                        DVec3::from_array(n),
                    )
                })
                .collect()
        })
        .collect()
}

#[test]
fn baked_colors_are_the_reference_on_geometry_placed_by_the_test() {
    let (model, expected) = hierarchy();
    // The accurate tier, stored as unorm16 in the display space: within
    // the tier's bound through sRGB's decoding, plus half a step of 16 bits.
    let tolerance = SRGB_SLOPE * 1e-5 + 0.5 / 65535.0 + 1e-6;
    let baked = read_glb(&bake(&model.glb(), &request(), Form::Glb));
    let references = reference_colors(&expected, false, Side::Front);
    for (e, reference) in expected.iter().zip(&references) {
        let accessor = baked
            .attribute(e.node, e.primitive, "COLOR_0")
            .expect("COLOR_0");
        let accessor_json = &baked.json["accessors"][accessor];
        assert_eq!(accessor_json["componentType"], 5123);
        assert_eq!(accessor_json["normalized"], true);
        let colors = baked.floats(accessor);
        assert_eq!(colors.len(), reference.len());
        for (v, (got, want)) in colors.iter().zip(reference).enumerate() {
            for k in 0..3 {
                let want = srgb_to_linear(want[k]);
                assert!(
                    (f64::from(got[k]) - want).abs() <= tolerance,
                    "node {} primitive {} vertex {v} channel {k}: {} against {want}",
                    e.node,
                    e.primitive,
                    got[k]
                );
            }
            assert!((f64::from(got[3]) - want.w).abs() <= 0.5 / 65535.0 + 1e-7);
        }
        assert!(
            baked
                .attribute(e.node, e.primitive, "_GL_BACK_COLOR")
                .is_none()
        );
    }
}

#[test]
fn every_precision_and_format_stays_within_its_bound() {
    let (model, expected) = hierarchy();
    let references = reference_colors(&expected, false, Side::Front);
    let glb = model.glb();
    for (precision, bound) in [
        ("reference", 6e-8),
        ("accurate", 1e-5),
        ("fast", 1.0 / 512.0),
    ] {
        for (format, step) in [
            ("float", 0.0),
            ("unorm16", 1.0 / 65535.0),
            ("unorm8", 1.0 / 255.0),
        ] {
            let mut request = request();
            request["precision"] = json!(precision);
            request["color_format"] = json!(format);
            request["color_space"] = json!("linear");
            let baked = read_glb(&bake(&glb, &request, Form::Glb));
            let tolerance = bound + step / 2.0 + 1e-7;
            for (e, reference) in expected.iter().zip(&references) {
                let colors = baked.floats(baked.attribute(e.node, e.primitive, "COLOR_0").unwrap());
                for (got, want) in colors.iter().zip(reference) {
                    for k in 0..4 {
                        let diff = (f64::from(got[k]) - want[k]).abs();
                        assert!(
                            diff <= tolerance,
                            "{precision} {format}: {got:?} against {want}"
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn two_sided_lighting_bakes_the_back_colors_too() {
    let (model, expected) = hierarchy();
    let mut request = request();
    request["light_model"]["two_side"] = json!(true);
    request["color_space"] = json!("linear");
    request["color_format"] = json!("float");
    let baked = read_glb(&bake(&model.glb(), &request, Form::Glb));
    for (side, name) in [(Side::Front, "COLOR_0"), (Side::Back, "_GL_BACK_COLOR")] {
        let references = reference_colors(&expected, true, side);
        for (e, reference) in expected.iter().zip(&references) {
            let colors = baked.floats(baked.attribute(e.node, e.primitive, name).unwrap());
            for (got, want) in colors.iter().zip(reference) {
                for k in 0..4 {
                    assert!((f64::from(got[k]) - want[k]).abs() <= 1e-5 + 1e-7, "{name}");
                }
            }
        }
    }
}

#[test]
fn the_baked_model_keeps_the_input_and_gives_a_further_node_its_own_mesh() {
    let (mut model, expected) = hierarchy();
    model.json["extras"] = json!({ "author": "the tests" });
    model.json["nodes"][0]["name"] = json!("root");
    model.json["meshes"][0]["extras"] = json!({ "kept": true });
    model.json["materials"][0]["extensions"] = json!({ "VENDOR_gloss": { "gloss": 1 } });
    model.json["extensionsUsed"] = json!(["VENDOR_gloss"]);
    let input = model.json.clone();
    let baked = read_glb(&bake(&model.glb(), &request(), Form::Glb));
    let out = &baked.json;

    // The second user of the tent gets a copy: one mesh more.
    let meshes = input["meshes"].as_array().unwrap().len();
    assert_eq!(out["meshes"].as_array().unwrap().len(), meshes + 1);
    let [first, .., last] = &expected[..] else {
        unreachable!()
    };
    assert_eq!(out["nodes"][first.node]["mesh"], 0);
    assert_eq!(out["nodes"][last.node]["mesh"], meshes);
    assert_eq!(out["meshes"][meshes]["extras"], json!({ "kept": true }));
    assert_ne!(
        baked.attribute(first.node, 0, "COLOR_0"),
        baked.attribute(last.node, 0, "COLOR_0")
    );
    // Everything else is kept.
    assert_eq!(out["extras"]["author"], "the tests");
    assert_eq!(out["nodes"][0]["name"], "root");
    assert_eq!(out["asset"], input["asset"]);
    for (k, accessor) in input["accessors"].as_array().unwrap().iter().enumerate() {
        assert_eq!(&out["accessors"][k], accessor);
    }
    for (k, view) in input["bufferViews"].as_array().unwrap().iter().enumerate() {
        assert_eq!(&out["bufferViews"][k], view);
    }
    let input_bin = model.bin.clone();
    assert_eq!(&baked.bin[..input_bin.len()], &input_bin[..]);
    for e in &expected {
        for attribute in ["POSITION", "NORMAL"] {
            let mesh = out["nodes"][e.node]["mesh"].as_u64().unwrap() as usize;
            let original = input["nodes"][e.node]["mesh"].as_u64().unwrap() as usize;
            assert_eq!(
                out["meshes"][mesh]["primitives"][e.primitive]["attributes"][attribute],
                input["meshes"][original]["primitives"][e.primitive]["attributes"][attribute]
            );
        }
    }
    // Each shaded material is an unlit copy with a white base colour; the
    // originals stay as they were.
    for (k, material) in input["materials"].as_array().unwrap().iter().enumerate() {
        assert_eq!(&out["materials"][k], material);
    }
    for e in &expected {
        let mesh = out["nodes"][e.node]["mesh"].as_u64().unwrap() as usize;
        let m = out["meshes"][mesh]["primitives"][e.primitive]["material"]
            .as_u64()
            .unwrap() as usize;
        let material = &out["materials"][m];
        assert_eq!(material["extensions"]["KHR_materials_unlit"], json!({}));
        assert_eq!(
            material["pbrMetallicRoughness"]["baseColorFactor"],
            json!([1.0, 1.0, 1.0, 1.0])
        );
    }
    assert_eq!(
        out["extensionsUsed"],
        json!(["VENDOR_gloss", "KHR_materials_unlit"])
    );
    assert!(out.get("extensionsRequired").is_none());
    // What glint says of the bake.
    let glint = &out["extras"]["glint"];
    let vertices: usize = expected.iter().map(|e| e.positions.len()).sum();
    assert_eq!(glint["stats"]["vertices"], vertices);
    assert_eq!(glint["stats"]["primitives"], expected.len());
    assert_eq!(glint["precision"]["mode"], "accurate");
    assert!(
        glint["modeled"]
            .as_array()
            .unwrap()
            .contains(&json!("lights[1].spot"))
    );
    let codes = warning_codes(&glint["warnings"]);
    assert_eq!(codes, ["normals_computed"], "{glint}");
    assert_eq!(glint["warnings"][0]["count"], 1);
}

#[test]
fn the_json_form_runs_match_the_baked_colors() {
    let (model, expected) = hierarchy();
    let mut request = request();
    request["color_space"] = json!("linear");
    request["color_format"] = json!("float");
    let glb = model.glb();
    let baked = read_glb(&bake(&glb, &request, Form::Glb));
    let answer: Value = serde_json::from_slice(&bake(&glb, &request, Form::Json)).unwrap();
    let runs = answer["primitives"].as_array().unwrap();
    assert_eq!(runs.len(), expected.len());
    let mut first = 0;
    for (run, e) in runs.iter().zip(&expected) {
        assert_eq!(run["node"], e.node);
        assert_eq!(run["primitive"], e.primitive);
        assert_eq!(run["first"], first);
        assert_eq!(run["count"], e.positions.len());
        let colors = baked.floats(baked.attribute(e.node, e.primitive, "COLOR_0").unwrap());
        for (k, c) in colors.iter().enumerate() {
            let json: Vec<f32> = answer["colors"][first + k]
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap() as f32)
                .collect();
            assert_eq!(&json, c);
        }
        first += e.positions.len();
    }
    assert_eq!(answer["colors"].as_array().unwrap().len(), first);
    assert_eq!(answer["stats"]["primitives"], expected.len());
}

#[test]
fn per_vertex_terms_are_baked_as_attributes() {
    let (model, expected) = hierarchy();
    let mut request = request();
    request["terms"] = json!("per_vertex");
    let baked = read_glb(&bake(&model.glb(), &request, Form::Glb));
    let (lights, material) = request_lighting(false);
    for e in &expected {
        let read = |name| baked.floats(baked.attribute(e.node, e.primitive, name).expect(name));
        let [emission, ambient, diffuse, specular] =
            ["_GL_EMISSION", "_GL_AMBIENT", "_GL_DIFFUSE", "_GL_SPECULAR"].map(read);
        for (v, (p, n)) in e.placed().into_iter().enumerate() {
            let b = reference::evaluate(
                &lights,
                &material(e.material),
                Side::Front,
                DVec3::from_array(p),
                DVec3::from_array(n),
            );
            let sums = [
                b.emission,
                b.lights.iter().fold(b.global_ambient, |s, l| s + l.ambient),
                b.lights.iter().map(|l| l.diffuse).sum(),
                b.lights.iter().map(|l| l.specular).sum(),
            ];
            for (got, want) in [&emission, &ambient, &diffuse, &specular].iter().zip(sums) {
                for k in 0..3 {
                    assert!(
                        (f64::from(got[v][k]) - want[k]).abs() <= 1e-6 * want[k].abs().max(1.0)
                    );
                }
            }
        }
    }
    assert!(
        baked.json["extras"]["glint"]["summary"]["vertices"]
            .as_u64()
            .unwrap()
            > 0
    );
}

/// A model with a camera, a point light, a spot light and a directional
/// light on nodes, and a metallic-roughness material, shaded with nothing
/// but the model: the mapping of `api/openapi.yaml`, computed here.
/// A tent of the material "brass" under a point, a spot and a
/// directional light, with a camera: each on a node.
pub fn lit_scene() -> (Gltf, usize) {
    let mut g = Gltf::new();
    let positions = g.vec3s(&TENT);
    let normals = g.vec3s(&tent_normals());
    let indices = g.indices(&TENT_INDICES, 5125);
    let material = g.material(json!({
        "name": "brass",
        "pbrMetallicRoughness": { "baseColorFactor": [0.8, 0.6, 0.2, 0.9], "metallicFactor": 0.7, "roughnessFactor": 0.5 },
        "emissiveFactor": [0.1, 0.0, 0.05]
    }));
    let mesh = g.mesh(json!([{ "attributes": { "POSITION": positions, "NORMAL": normals }, "indices": indices, "material": material }]));
    g.json["extensionsUsed"] = json!(["KHR_lights_punctual"]);
    g.json["extensions"] = json!({ "KHR_lights_punctual": { "lights": [
        { "type": "point", "color": [1.0, 0.9, 0.8], "intensity": 5.0 },
        { "type": "spot", "intensity": 3.0, "spot": { "innerConeAngle": 0.2, "outerConeAngle": 0.6 } },
        { "type": "directional", "color": [0.5, 0.5, 1.0], "intensity": 0.8 }
    ] } });
    g.json["cameras"] =
        json!([{ "type": "perspective", "perspective": { "yfov": 0.8, "znear": 0.1 } }]);
    // The camera at (0, 3, 6) looking down by 30° about x.
    let tilt = (-15f64).to_radians();
    let camera = g.node(json!({ "camera": 0, "translation": [0, 3, 6], "rotation": [tilt.sin(), 0, 0, tilt.cos()] }));
    let point_light = g.node(json!({ "translation": [1, 2, 2], "extensions": { "KHR_lights_punctual": { "light": 0 } } }));
    // The spot points along its node's −z: rotated to point down.
    let down = (-45f64).to_radians();
    let spot_light = g.node(
        json!({ "translation": [0, 3, 0], "rotation": [down.sin(), 0, 0, down.cos()],
                                    "extensions": { "KHR_lights_punctual": { "light": 1 } } }),
    );
    let sun = g.node(json!({ "rotation": [down.sin(), 0, 0, down.cos()], "extensions": { "KHR_lights_punctual": { "light": 2 } } }));
    let tent = g.node(json!({ "mesh": mesh }));
    g.scene(&[camera, point_light, spot_light, sun, tent]);
    (g, tent)
}

#[test]
fn lights_materials_and_the_view_come_from_the_model() {
    let (g, tent) = lit_scene();
    let down = (-45f64).to_radians();
    let request = json!({ "light_model": { "local_viewer": true }, "precision": "reference", "color_space": "linear", "color_format": "float" });
    let answer: Value = serde_json::from_slice(&bake(&g.glb(), &request, Form::Json)).unwrap();

    // The mapping, by the formulas of the contract.
    let rotate_x = |angle: f64, v: [f64; 3]| {
        let (c, s) = ((2.0 * angle).cos(), (2.0 * angle).sin());
        [v[0], c * v[1] - s * v[2], s * v[1] + c * v[2]]
    };
    let spot_axis = rotate_x(down, [0.0, 0.0, -1.0]);
    let (cos_i, cos_o) = (0.2f64.cos(), 0.6f64.cos());
    let exponent = 0.5f64.ln() / (cos_o + (cos_i - cos_o) / 2f64.sqrt()).ln();
    let color = |c: [f64; 3], i: f64| DVec4::new(c[0] * i, c[1] * i, c[2] * i, 1.0);
    let lights = vec![
        Light {
            position: LightPosition::Positional(DVec3::new(1.0, 2.0, 2.0)),
            diffuse: color([1.0, 0.9, 0.8], 5.0),
            specular: color([1.0, 0.9, 0.8], 5.0),
            attenuation: [0.0, 0.0, 1.0],
            ..Light::default()
        },
        Light {
            position: LightPosition::Positional(DVec3::new(0.0, 3.0, 0.0)),
            diffuse: color([1.0; 3], 3.0),
            specular: color([1.0; 3], 3.0),
            attenuation: [0.0, 0.0, 1.0],
            spot: Spot {
                direction: DVec3::from_array(spot_axis),
                exponent,
                cutoff: 0.6f64.to_degrees(),
            },
            ..Light::default()
        },
        Light {
            position: LightPosition::Directional(-DVec3::from_array(spot_axis)),
            diffuse: color([0.5, 0.5, 1.0], 0.8),
            specular: color([0.5, 0.5, 1.0], 0.8),
            ..Light::default()
        },
    ];
    let model = LightModel {
        local_viewer: true,
        ..LightModel::default()
    };
    let lights = LightSet::new(model, lights, Viewer::Local(DVec3::new(0.0, 3.0, 6.0))).unwrap();
    let base = DVec4::new(0.8, 0.6, 0.2, 0.9);
    let f0 = DVec3::splat(0.04) * (1.0 - 0.7) + base.truncate() * 0.7;
    let brass = Material {
        ambient: base,
        diffuse: base,
        specular: (f0 * 0.5).extend(1.0),
        emission: DVec4::new(0.1, 0.0, 0.05, 1.0),
        shininess: 2.0 / 0.5f64.powi(4) - 2.0,
    };
    let e = Expected {
        node: tent,
        primitive: 0,
        world: IDENTITY,
        positions: TENT.iter().map(|p| p.map(f64::from)).collect(),
        normals: Some(tent_normals().iter().map(|p| p.map(f64::from)).collect()),
        triangles: vec![],
        material: "brass",
    };
    for (v, (p, n)) in e.placed().into_iter().enumerate() {
        let want = reference::color(
            &lights,
            &SurfaceMaterial::both_sides(brass),
            Side::Front,
            DVec3::from_array(p),
            DVec3::from_array(n),
        );
        for k in 0..4 {
            let got = answer["colors"][v][k].as_f64().unwrap();
            assert!(
                (got - want[k]).abs() <= 1e-6,
                "vertex {v}: {} against {want}",
                answer["colors"][v]
            );
        }
    }
    let codes = warning_codes(&answer["warnings"]);
    assert_eq!(
        codes,
        ["spot_falloff_fitted", "pbr_approximated"],
        "{}",
        answer["warnings"]
    );
    assert_eq!(
        answer["modeled"],
        json!([
            "emission",
            "global_ambient",
            "lights[0].diffuse",
            "lights[0].specular",
            "lights[0].attenuation",
            "lights[1].diffuse",
            "lights[1].specular",
            "lights[1].attenuation",
            "lights[1].spot",
            "lights[2].diffuse",
            "lights[2].specular"
        ])
    );
}
