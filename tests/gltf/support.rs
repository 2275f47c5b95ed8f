//! What the glTF tests build and check with, written here apart from
//! glint's own code: a GLB builder (accessors packed, interleaved or
//! sparse; nodes; materials), the tests' own 4×4 matrix arithmetic (TRS
//! composition, the inverse transpose by cofactors), and a reader of the
//! accessors glint writes.

use serde_json::{Value, json};

/// A glTF model being built: its JSON and its one buffer.
pub struct Gltf {
    pub json: Value,
    pub bin: Vec<u8>,
}

impl Default for Gltf {
    fn default() -> Self {
        Self::new()
    }
}

fn push(json: &mut Value, name: &str, value: Value) -> usize {
    let slot = &mut json[name];
    if !slot.is_array() {
        *slot = json!([]);
    }
    let array = slot.as_array_mut().unwrap();
    array.push(value);
    array.len() - 1
}

fn f32_bytes(values: impl IntoIterator<Item = f32>) -> Vec<u8> {
    values.into_iter().flat_map(f32::to_le_bytes).collect()
}

impl Gltf {
    pub fn new() -> Self {
        Self {
            json: json!({ "asset": { "version": "2.0", "generator": "glint tests" } }),
            bin: Vec::new(),
        }
    }

    /// Appends `bytes` (from a multiple of 4) as a buffer view.
    pub fn view(&mut self, bytes: &[u8], stride: Option<usize>) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let mut view =
            json!({ "buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len() });
        if let Some(stride) = stride {
            view["byteStride"] = json!(stride);
        }
        self.bin.extend_from_slice(bytes);
        push(&mut self.json, "bufferViews", view)
    }

    pub fn accessor(&mut self, accessor: Value) -> usize {
        push(&mut self.json, "accessors", accessor)
    }

    /// A packed VEC3 float accessor, with the min and max POSITION needs.
    pub fn vec3s(&mut self, values: &[[f32; 3]]) -> usize {
        let view = self.view(&f32_bytes(values.iter().flatten().copied()), None);
        let accessor = vec3_accessor(view, 0, values);
        self.accessor(accessor)
    }

    /// Positions and normals interleaved in one buffer view of stride 24,
    /// after 8 bytes of something else: two accessors.
    pub fn interleaved(&mut self, positions: &[[f32; 3]], normals: &[[f32; 3]]) -> (usize, usize) {
        let mut bytes = vec![0xAB; 8];
        for (p, n) in positions.iter().zip(normals) {
            bytes.extend(f32_bytes(p.iter().chain(n).copied()));
        }
        let view = self.view(&bytes, Some(24));
        let p = self.accessor(vec3_accessor(view, 8, positions));
        let n = self.accessor(vec3_accessor(view, 20, normals));
        (p, n)
    }

    /// A VEC3 float accessor of `base` with the entries of `substitutions`
    /// replaced through a sparse accessor; `base` `None`: zeros, with no
    /// buffer view at all.
    pub fn sparse_vec3s(
        &mut self,
        count: usize,
        base: Option<&[[f32; 3]]>,
        substitutions: &[(u16, [f32; 3])],
    ) -> usize {
        let mut full = match base {
            Some(b) => b.to_vec(),
            None => vec![[0.0; 3]; count],
        };
        for &(i, v) in substitutions {
            full[i as usize] = v;
        }
        let indices: Vec<u8> = substitutions
            .iter()
            .flat_map(|(i, _)| i.to_le_bytes())
            .collect();
        let values = f32_bytes(substitutions.iter().flat_map(|(_, v)| *v));
        let indices_view = self.view(&indices, None);
        let values_view = self.view(&values, None);
        let mut accessor = vec3_accessor(0, 0, &full);
        match base {
            Some(b) => {
                accessor["bufferView"] =
                    json!(self.view(&f32_bytes(b.iter().flatten().copied()), None))
            }
            None => {
                accessor.as_object_mut().unwrap().remove("bufferView");
                accessor.as_object_mut().unwrap().remove("byteOffset");
            }
        }
        accessor["sparse"] = json!({
            "count": substitutions.len(),
            "indices": { "bufferView": indices_view, "componentType": 5123 },
            "values": { "bufferView": values_view },
        });
        self.accessor(accessor)
    }

    /// A packed SCALAR accessor of indices in `component_type` (5121,
    /// 5123 or 5125).
    pub fn indices(&mut self, indices: &[u32], component_type: u32) -> usize {
        let bytes: Vec<u8> = match component_type {
            5121 => indices.iter().map(|&i| i as u8).collect(),
            5123 => indices
                .iter()
                .flat_map(|&i| (i as u16).to_le_bytes())
                .collect(),
            5125 => indices.iter().flat_map(|&i| i.to_le_bytes()).collect(),
            _ => panic!("not an index type"),
        };
        let view = self.view(&bytes, None);
        self.accessor(json!({
            "bufferView": view, "componentType": component_type,
            "count": indices.len(), "type": "SCALAR"
        }))
    }

    pub fn mesh(&mut self, primitives: Value) -> usize {
        push(
            &mut self.json,
            "meshes",
            json!({ "primitives": primitives }),
        )
    }

    pub fn node(&mut self, node: Value) -> usize {
        push(&mut self.json, "nodes", node)
    }

    pub fn material(&mut self, material: Value) -> usize {
        push(&mut self.json, "materials", material)
    }

    /// The default scene, of `roots`.
    pub fn scene(&mut self, roots: &[usize]) {
        let scene = push(&mut self.json, "scenes", json!({ "nodes": roots }));
        self.json["scene"] = json!(scene);
    }

    /// The GLB: header, JSON chunk, BIN chunk, each padded to 4 bytes.
    pub fn glb(&self) -> Vec<u8> {
        let mut json = self.json.clone();
        if !self.bin.is_empty() && json.get("buffers").is_none() {
            json["buffers"] = json!([{ "byteLength": self.bin.len() }]);
        }
        glb(&serde_json::to_vec(&json).unwrap(), &self.bin)
    }
}

fn vec3_accessor(view: usize, offset: usize, values: &[[f32; 3]]) -> Value {
    let mut min = [f32::INFINITY; 3];
    let mut max = [f32::NEG_INFINITY; 3];
    for v in values {
        for k in 0..3 {
            min[k] = min[k].min(v[k]);
            max[k] = max[k].max(v[k]);
        }
    }
    json!({
        "bufferView": view, "byteOffset": offset, "componentType": 5126,
        "count": values.len(), "type": "VEC3", "min": min, "max": max
    })
}

/// A GLB of `json` and `bin` (no BIN chunk when it is empty).
pub fn glb(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let pad = |n: usize| n.div_ceil(4) * 4;
    let mut chunks = Vec::new();
    let mut json = json.to_vec();
    json.resize(pad(json.len()), b' ');
    chunks.extend((json.len() as u32).to_le_bytes());
    chunks.extend(b"JSON");
    chunks.extend(&json);
    if !bin.is_empty() {
        let mut bin = bin.to_vec();
        bin.resize(pad(bin.len()), 0);
        chunks.extend((bin.len() as u32).to_le_bytes());
        chunks.extend(b"BIN\0");
        chunks.extend(&bin);
    }
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend(((12 + chunks.len()) as u32).to_le_bytes());
    out.extend(chunks);
    out
}

/// A GLB as the tests read it: the JSON, and the BIN chunk.
pub struct Read {
    pub json: Value,
    pub bin: Vec<u8>,
}

/// Splits a GLB into its JSON and BIN chunk, checking its header.
pub fn read_glb(bytes: &[u8]) -> Read {
    let word = |o: usize| u32::from_le_bytes(bytes[o..o + 4].try_into().unwrap()) as usize;
    assert_eq!(&bytes[..4], b"glTF");
    assert_eq!(word(4), 2);
    assert_eq!(word(8), bytes.len());
    let json_len = word(12);
    assert_eq!(&bytes[16..20], b"JSON");
    let json = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
    let at = 20 + json_len;
    let bin = if at < bytes.len() {
        assert_eq!(&bytes[at + 4..at + 8], b"BIN\0");
        bytes[at + 8..at + 8 + word(at)].to_vec()
    } else {
        Vec::new()
    };
    assert!(bytes.len().is_multiple_of(4));
    Read { json, bin }
}

impl Read {
    /// The values of a packed accessor, as floats: normalised unsigned
    /// integers divided by their maximum.
    pub fn floats(&self, accessor: usize) -> Vec<Vec<f32>> {
        let a = &self.json["accessors"][accessor];
        let v = &self.json["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
        assert!(v.get("byteStride").is_none(), "packed");
        let components = match a["type"].as_str().unwrap() {
            "VEC3" => 3,
            "VEC4" => 4,
            other => panic!("{other}"),
        };
        let start = v["byteOffset"].as_u64().unwrap_or(0) as usize
            + a["byteOffset"].as_u64().unwrap_or(0) as usize;
        let count = a["count"].as_u64().unwrap() as usize;
        let normalized = a["normalized"].as_bool().unwrap_or(false);
        let component = a["componentType"].as_u64().unwrap();
        let size = match component {
            5121 => 1,
            5123 => 2,
            5126 => 4,
            other => panic!("{other}"),
        };
        assert!(component == 5126 || normalized);
        let bytes = &self.bin[start..start + count * components * size];
        bytes
            .chunks_exact(components * size)
            .map(|e| {
                e.chunks_exact(size)
                    .map(|c| match component {
                        5121 => f32::from(c[0]) / 255.0,
                        5123 => f32::from(u16::from_le_bytes([c[0], c[1]])) / 65535.0,
                        _ => f32::from_le_bytes(c.try_into().unwrap()),
                    })
                    .collect()
            })
            .collect()
    }

    /// The accessor of attribute `name` of primitive `primitive` of the
    /// mesh that node `node` shows.
    pub fn attribute(&self, node: usize, primitive: usize, name: &str) -> Option<usize> {
        let mesh = self.json["nodes"][node]["mesh"].as_u64().unwrap() as usize;
        self.json["meshes"][mesh]["primitives"][primitive]["attributes"][name]
            .as_u64()
            .map(|a| a as usize)
    }
}

/// A 4×4 matrix, rows of columns: `m[row][column]`.
pub type M4 = [[f64; 4]; 4];

pub const IDENTITY: M4 = [
    [1.0, 0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0, 0.0],
    [0.0, 0.0, 1.0, 0.0],
    [0.0, 0.0, 0.0, 1.0],
];

pub fn mul(a: &M4, b: &M4) -> M4 {
    let mut c = [[0.0; 4]; 4];
    for (i, row) in c.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = (0..4).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

/// T · R · S of a node, the rotation from its unit quaternion `[x, y, z, w]`.
pub fn trs(t: [f64; 3], q: [f64; 4], s: [f64; 3]) -> M4 {
    let [x, y, z, w] = q;
    let r = [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - z * w),
            2.0 * (x * z + y * w),
        ],
        [
            2.0 * (x * y + z * w),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - x * w),
        ],
        [
            2.0 * (x * z - y * w),
            2.0 * (y * z + x * w),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ];
    let mut m = IDENTITY;
    for i in 0..3 {
        for j in 0..3 {
            m[i][j] = r[i][j] * s[j];
        }
        m[i][3] = t[i];
    }
    m
}

/// glTF's column-major `matrix` as [`M4`].
pub fn from_columns(c: &[f64; 16]) -> M4 {
    let mut m = [[0.0; 4]; 4];
    for (j, column) in c.chunks_exact(4).enumerate() {
        for i in 0..4 {
            m[i][j] = column[i];
        }
    }
    m
}

pub fn point(m: &M4, p: [f64; 3]) -> [f64; 3] {
    let r = |i: usize| m[i][0] * p[0] + m[i][1] * p[1] + m[i][2] * p[2] + m[i][3];
    [r(0), r(1), r(2)]
}

/// The upper 3×3's determinant.
pub fn determinant(m: &M4) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// `n` by the inverse transpose of the upper 3×3: its cofactor matrix over
/// its determinant.
pub fn normal(m: &M4, n: [f64; 3]) -> [f64; 3] {
    let c = |i: usize, j: usize| {
        let (r0, r1) = ((i + 1) % 3, (i + 2) % 3);
        let (c0, c1) = ((j + 1) % 3, (j + 2) % 3);
        m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0]
    };
    let d = determinant(m);
    let r = |i: usize| (c(i, 0) * n[0] + c(i, 1) * n[1] + c(i, 2) * n[2]) / d;
    [r(0), r(1), r(2)]
}

pub fn unit(v: [f64; 3]) -> [f64; 3] {
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    v.map(|x| x / l)
}

pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

pub fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// sRGB's decoding (IEC 61966-2-1), in f64.
pub fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The largest slope of [`srgb_to_linear`] on [0, 1], at 1: an error `e`
/// in a colour is at most this times `e` once decoded.
pub const SRGB_SLOPE: f64 = 2.4 / 1.055;

/// The codes of a list of warnings, in order.
pub fn warning_codes(warnings: &Value) -> Vec<&str> {
    warnings
        .as_array()
        .expect("warnings are a list")
        .iter()
        .map(|w| w["code"].as_str().expect("a warning has a code"))
        .collect()
}
