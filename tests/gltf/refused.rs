//! Models that lie, or that glint cannot honour, each refused with the
//! pointer of its fault and before anything is allocated from what it
//! claims: in the library, and over HTTP with the server serving the next
//! request.

use glint::scene::{Limits, RequestErrorKind, parse_bake};
use serde_json::json;

use super::bake::{TENT, TENT_INDICES};
use super::support::*;

/// A lying model, and how it must be refused.
pub struct Case {
    pub name: &'static str,
    pub glb: Vec<u8>,
    pub kind: RequestErrorKind,
    pub pointer: &'static str,
}

/// The tent with positions, normals and indices: accessors 0, 1, 2 over
/// buffer views 0, 1, 2.
pub fn tent() -> Gltf {
    let mut g = Gltf::new();
    let positions = g.vec3s(&TENT);
    let normals = g.vec3s(&TENT);
    let indices = g.indices(&TENT_INDICES, 5123);
    let mesh = g.mesh(
        json!([{ "attributes": { "POSITION": positions, "NORMAL": normals }, "indices": indices }]),
    );
    let node = g.node(json!({ "mesh": mesh }));
    g.scene(&[node]);
    g
}

/// `tent` with its JSON changed by `edit`.
fn edited(edit: impl FnOnce(&mut Gltf)) -> Vec<u8> {
    let mut g = tent();
    edit(&mut g);
    g.glb()
}

pub fn cases() -> Vec<Case> {
    use RequestErrorKind::*;
    let valid = tent().glb();
    let json_length_at = 12;
    let bin_length_at = {
        let json_length = u32::from_le_bytes(valid[12..16].try_into().unwrap()) as usize;
        20 + json_length
    };
    let with_word = |at: usize, value: u32| {
        let mut glb = valid.clone();
        glb[at..at + 4].copy_from_slice(&value.to_le_bytes());
        glb
    };
    let case = |name, glb, kind, pointer| Case {
        name,
        glb,
        kind,
        pointer,
    };
    vec![
        case("an empty body", Vec::new(), Malformed, "/model"),
        case(
            "a truncated GLB",
            valid[..valid.len() / 2].to_vec(),
            Malformed,
            "/model",
        ),
        case(
            "not a GLB",
            b"{\"asset\":{\"version\":\"2.0\"}}".to_vec(),
            Malformed,
            "/model",
        ),
        case(
            "a JSON chunk length past the body",
            with_word(json_length_at, 0x7fff_0000),
            Malformed,
            "/model",
        ),
        case(
            "a BIN chunk length past the body",
            with_word(bin_length_at, u32::MAX - 3),
            Malformed,
            "/model",
        ),
        case(
            "a JSON chunk that is not JSON",
            glb(b"{\"asset\": [", &[]),
            Malformed,
            "/model",
        ),
        case(
            "a buffer longer than the BIN chunk",
            edited(|g| g.json["buffers"] = json!([{ "byteLength": 1_000_000 }])),
            Invalid,
            "/model/buffers/0/byteLength",
        ),
        case(
            "an accessor past its buffer view",
            edited(|g| g.json["accessors"][0]["count"] = json!(6)),
            Invalid,
            "/model/accessors/0/count",
        ),
        case(
            "an accessor's offset past its buffer view",
            edited(|g| g.json["accessors"][1]["byteOffset"] = json!(4)),
            Invalid,
            "/model/accessors/1/count",
        ),
        case(
            "a buffer view past the buffer",
            edited(|g| g.json["bufferViews"][1]["byteLength"] = json!(4096)),
            Invalid,
            "/model/bufferViews/1/byteLength",
        ),
        case(
            "count × byteStride overflowing",
            edited(|g| {
                g.json["bufferViews"][0]["byteStride"] = json!(252);
                g.json["accessors"][0]["count"] = json!(u64::MAX / 8);
            }),
            Invalid,
            "/model/accessors/0/count",
        ),
        case(
            "2^32 vertices claimed in a small body",
            edited(|g| g.json["accessors"][0]["count"] = json!(1u64 << 32)),
            Invalid,
            "/model/accessors/0/count",
        ),
        case(
            "2^32 vertices claimed without a buffer view",
            edited(|g| {
                g.json["accessors"][0]
                    .as_object_mut()
                    .unwrap()
                    .remove("bufferView");
                g.json["accessors"][0]["count"] = json!(1u64 << 32);
            }),
            OverLimit,
            "/model/accessors/0/count",
        ),
        case(
            "indices past the vertex count",
            {
                let mut g = Gltf::new();
                let p = g.vec3s(&TENT);
                let i = g.indices(&[0, 1, 5], 5121);
                let mesh = g.mesh(json!([{ "attributes": { "POSITION": p }, "indices": i }]));
                let node = g.node(json!({ "mesh": mesh }));
                g.scene(&[node]);
                g.glb()
            },
            Invalid,
            "/model/meshes/0/primitives/0/indices",
        ),
        case(
            "a non-finite float in POSITION",
            {
                let mut g = tent();
                // The fourth vertex's y, in the positions' buffer view.
                g.bin[3 * 12 + 4..3 * 12 + 8].copy_from_slice(&f32::NAN.to_le_bytes());
                g.glb()
            },
            Invalid,
            "/model/accessors/0",
        ),
        case(
            "a required extension glint does not read",
            edited(|g| {
                g.json["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
                g.json["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
            }),
            Unsupported,
            "/model/extensionsRequired/0",
        ),
        case(
            "an external URI",
            edited(|g| {
                g.json["buffers"] = json!([{ "byteLength": 4, "uri": "file:///etc/passwd" }]);
            }),
            Invalid,
            "/model/buffers/0/uri",
        ),
        case(
            "a data URI",
            edited(|g| {
                g.json["buffers"] = json!([{ "byteLength": 4, "uri": "data:application/octet-stream;base64,AAAAAA==" }]);
            }),
            Invalid,
            "/model/buffers/0/uri",
        ),
        case(
            "a node that is its own ancestor",
            edited(|g| g.json["nodes"][0]["children"] = json!([0])),
            Invalid,
            "/model/nodes/0/children/0",
        ),
        case(
            "a mesh that does not exist",
            edited(|g| g.json["nodes"][0]["mesh"] = json!(7)),
            Invalid,
            "/model/nodes/0/mesh",
        ),
        case(
            "a count that is not a number",
            edited(|g| g.json["accessors"][2]["count"] = json!("twelve")),
            Malformed,
            "/model/accessors/2/count",
        ),
        case(
            "a stride that is not a multiple of 4",
            edited(|g| g.json["bufferViews"][0]["byteStride"] = json!(13)),
            Invalid,
            "/model/bufferViews/0/byteStride",
        ),
        case(
            "a glTF 1 model",
            edited(|g| g.json["asset"]["version"] = json!("1.0")),
            Unsupported,
            "/model/asset/version",
        ),
    ]
}

#[test]
fn each_lying_model_is_refused_with_the_pointer_of_its_fault() {
    for case in cases() {
        let e = parse_bake(None, &case.glb, &Limits::default())
            .map(|_| ())
            .expect_err(case.name);
        assert_eq!(
            (e.kind, e.pointer.as_str()),
            (case.kind, case.pointer),
            "{}: {e}",
            case.name
        );
    }
}

#[test]
fn a_mesh_used_by_many_nodes_counts_against_the_vertex_limit() {
    let mut g = tent();
    let nodes: Vec<usize> = (0..10).map(|_| g.node(json!({ "mesh": 0 }))).collect();
    g.scene(&nodes);
    let limits = Limits {
        max_vertices: 5 * 9,
        ..Limits::default()
    };
    let e = parse_bake(None, &g.glb(), &limits).map(|_| ()).unwrap_err();
    assert_eq!(e.kind, RequestErrorKind::OverLimit, "{e}");
    assert_eq!(
        e.pointer,
        "/model/meshes/0/primitives/0/attributes/POSITION"
    );
    let limits = Limits {
        max_vertices: 5 * 10,
        ..Limits::default()
    };
    assert!(parse_bake(None, &g.glb(), &limits).is_ok());
}

#[test]
fn request_part_errors_point_into_the_request() {
    let glb = tent().glb();
    let cases = [
        (
            json!({ "lights": [{ "spot": { "cutoff": 120 } }] }),
            "/request/lights/0/spot/cutoff",
        ),
        (
            json!({ "vertices": { "positions": [], "normals": [] } }),
            "/request/vertices",
        ),
        (
            json!({ "materials": { "nothing": {} } }),
            "/request/materials/nothing",
        ),
        (
            json!({ "color_format": "unorm32" }),
            "/request/color_format",
        ),
    ];
    for (request, pointer) in cases {
        let body = serde_json::to_vec(&request).unwrap();
        let e = parse_bake(Some(&body), &glb, &Limits::default())
            .map(|_| ())
            .unwrap_err();
        assert_eq!(e.pointer, pointer, "{request}: {e}");
    }
}
