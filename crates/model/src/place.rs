//! The default scene's triangles as its nodes place them (glTF 2.0,
//! sections 3.5 and 3.7.2): every node's world matrix in f64, positions by
//! it, normals by its inverse transpose, the winding of a mirrored node
//! (negative determinant) reversed so that a triangle's front stays where
//! its normals point, and smooth normals where a primitive has none.
//!
//! The scene is walked depth first, its root nodes and each node's
//! children in order; a node is visited once, so a cycle or a node with two
//! parents is refused rather than followed. A mesh used by several nodes is
//! placed once per node.

use glam::{DMat3, DMat4, DQuat, DVec3};

use crate::error::{Error, Result};
use crate::schema::{self, Node, TRIANGLES};
use rayon::prelude::*;

use crate::{MAX_PRIMITIVES, Model, Options, TRIANGLES_PER_VERTEX};

/// One triangle primitive as one node places it.
#[derive(Clone, Debug, PartialEq)]
pub struct Instance {
    pub node: usize,
    pub mesh: usize,
    /// Its index in the mesh's `primitives`.
    pub primitive: usize,
    /// Its material, `None` for glTF's default material.
    pub material: Option<usize>,
    /// In world space.
    pub positions: Vec<DVec3>,
    /// One per position, in world space: the model's normals by the
    /// inverse transpose of the node's matrix (unit length when the options
    /// ask for GL_NORMALIZE), or computed when it has none. Zero where the
    /// node's matrix is singular.
    pub normals: Vec<DVec3>,
    /// Three vertex indices per triangle, each within `positions`, wound
    /// counter-clockwise seen from the front in world space; empty unless
    /// [`Options::keep_triangles`] or the normals were computed from them.
    pub triangles: Vec<[u32; 3]>,
    /// The normals were computed: the primitive has no `NORMAL`.
    pub normals_computed: bool,
    /// The primitive's vertices (or indices) end with an incomplete
    /// triangle, one or two left over past the last multiple of 3: its
    /// vertices are placed (and lit), the triangle is not drawn. glTF asks
    /// for a multiple of 3, and Khronos' validator only warns about it.
    pub incomplete_triangle: bool,
}

/// A camera of the scene, where its node puts it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlacedCamera {
    pub node: usize,
    pub camera: usize,
    pub world: DMat4,
}

/// A `KHR_lights_punctual` light, where its node puts it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlacedLight {
    pub node: usize,
    pub light: usize,
    pub world: DMat4,
}

/// What [`Model::place`] found in the default scene.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Placed {
    /// In scene order: nodes depth first, a node's primitives in order.
    pub instances: Vec<Instance>,
    /// The cameras of the scene's nodes, in scene order.
    pub cameras: Vec<PlacedCamera>,
    /// The lights of the scene's nodes, in scene order.
    pub lights: Vec<PlacedLight>,
    /// Whether the model has a scene to place (`scene`, else the first).
    pub has_scene: bool,
    /// Primitives of another mode than triangles, not placed.
    pub not_triangles: usize,
    /// Triangle primitives with morph targets, placed without them.
    pub morph_targets: usize,
    /// Triangle primitives of skinned nodes, placed by their node's matrix
    /// (in bind pose).
    pub skinned: usize,
}

impl Model<'_> {
    /// The default scene's triangle primitives, placed.
    pub fn place(&self, options: &Options) -> Result<Placed> {
        let mut placed = Placed::default();
        let Some((scene_at, scene)) = self.default_scene()? else {
            return Ok(placed);
        };
        placed.has_scene = true;
        let meshes = self.walk(&scene_at, &scene, &mut placed)?;

        let mut vertices = 0usize;
        let mut triangles = 0usize;
        let mut primitives = 0usize;
        for (node, mesh_index, world) in meshes {
            let mesh_at = format!("/meshes/{mesh_index}");
            let mesh: schema::Mesh = self.get(&mesh_at)?;
            let skinned = self.get::<Node>(&format!("/nodes/{node}"))?.skin.is_some();
            for (p, primitive) in mesh.primitives.iter().enumerate() {
                if primitive.mode != TRIANGLES {
                    placed.not_triangles += 1;
                    continue;
                }
                primitives += 1;
                if primitives > MAX_PRIMITIVES {
                    return Err(Error::over_limit(
                        format!("/nodes/{node}/mesh"),
                        format!(
                            "more than {MAX_PRIMITIVES} triangle primitives placed (a mesh \
                             counts once per node that uses it)"
                        ),
                    ));
                }
                placed.morph_targets += usize::from(primitive.targets.is_some());
                placed.skinned += usize::from(skinned);
                let at = format!("{mesh_at}/primitives/{p}");
                let budget = Budget {
                    vertices: options.max_vertices - vertices,
                    triangles: options.max_vertices.saturating_mul(TRIANGLES_PER_VERTEX)
                        - triangles,
                    max_vertices: options.max_vertices,
                };
                let instance = self.instance(
                    node, mesh_index, p, primitive, &world, &at, options, &budget,
                )?;
                vertices += instance.positions.len();
                triangles += instance.triangles.len();
                placed.instances.push(instance);
            }
        }
        Ok(placed)
    }

    /// The scene to place and where it is: `scene`, else the first of
    /// `scenes`; `None` when there is none.
    fn default_scene(&self) -> Result<Option<(String, schema::Scene)>> {
        let index = match self.json.get("scene") {
            Some(_) => self.get::<usize>("/scene")?,
            None if self.count("scenes") > 0 => 0,
            None => return Ok(None),
        };
        let at = format!("/scenes/{index}");
        let scene = self.entry("scenes", index, "/scene")?;
        Ok(Some((at, scene)))
    }

    /// Walks the scene's node trees: the nodes with meshes and their world
    /// matrices, in order; cameras and lights into `placed`.
    fn walk(
        &self,
        scene_at: &str,
        scene: &schema::Scene,
        placed: &mut Placed,
    ) -> Result<Vec<(usize, usize, DMat4)>> {
        let nodes = self.count("nodes");
        let mut visited = vec![false; nodes];
        let mut meshes = Vec::new();
        // (node, where it is referred to, its parent's world matrix)
        let mut stack: Vec<(usize, String, DMat4)> = scene
            .nodes
            .iter()
            .enumerate()
            .rev()
            .map(|(k, &n)| (n, format!("{scene_at}/nodes/{k}"), DMat4::IDENTITY))
            .collect();
        while let Some((index, referrer, parent)) = stack.pop() {
            if index >= nodes {
                return Err(Error::invalid(
                    referrer,
                    format!("refers to node {index}, and the model has {nodes}"),
                ));
            }
            if std::mem::replace(&mut visited[index], true) {
                return Err(Error::invalid(
                    referrer,
                    format!(
                        "node {index} is reached twice: a node has one parent and no cycle \
                         leads back to it"
                    ),
                ));
            }
            let at = format!("/nodes/{index}");
            let node: Node = self.get(&at)?;
            let world = parent * local_matrix(&node, &at)?;
            if let Some(mesh) = node.mesh {
                if mesh >= self.count("meshes") {
                    return Err(Error::invalid(
                        format!("{at}/mesh"),
                        format!(
                            "refers to mesh {mesh}, and the model has {}",
                            self.count("meshes")
                        ),
                    ));
                }
                meshes.push((index, mesh, world));
            }
            if let Some(camera) = node.camera {
                placed.cameras.push(PlacedCamera {
                    node: index,
                    camera,
                    world,
                });
            }
            if let Some(light) = node.extensions.and_then(|e| e.lights_punctual) {
                placed.lights.push(PlacedLight {
                    node: index,
                    light: light.light,
                    world,
                });
            }
            for (k, &child) in node.children.iter().enumerate().rev() {
                stack.push((child, format!("{at}/children/{k}"), world));
            }
        }
        Ok(meshes)
    }

    #[allow(clippy::too_many_arguments)]
    fn instance(
        &self,
        node: usize,
        mesh: usize,
        p: usize,
        primitive: &schema::Primitive,
        world: &DMat4,
        at: &str,
        options: &Options,
        budget: &Budget,
    ) -> Result<Instance> {
        let attributes_at = format!("{at}/attributes");
        let Some(&position_accessor) = primitive.attributes.get("POSITION") else {
            return Err(Error::invalid(
                attributes_at,
                "a triangle primitive needs POSITION",
            ));
        };
        let position_at = format!("{attributes_at}/POSITION");
        // What an accessor with a buffer view claims is bounded by its
        // bytes, and checked against them; one without, by the budget.
        let positions = self.vec3s(position_accessor, &position_at, budget.vertices, |p| {
            world.transform_point3(DVec3::from_array(p.map(f64::from)))
        })?;
        let n = positions.len();
        if n > budget.vertices {
            return Err(Error::over_limit(
                position_at,
                format!(
                    "{n} more vertices, past the limit of {} placed vertices (a mesh counts \
                     once per node that uses it)",
                    budget.max_vertices
                ),
            ));
        }
        let outside =
            |p: &DVec3| !(p.is_finite() && p.abs().max_element() <= options.max_coordinate);
        if let Some(k) = positions
            .par_iter()
            .with_min_len(TASK_VERTICES)
            .position_first(outside)
        {
            return Err(Error::invalid(
                format!("/nodes/{node}"),
                format!(
                    "the node places vertex {k} of {position_at} at {:?}, beyond ±{:e}",
                    positions[k].to_array(),
                    options.max_coordinate
                ),
            ));
        }

        let linear = DMat3::from_mat4(*world);
        let determinant = linear.determinant();
        let mirrored = determinant < 0.0;
        let normal_accessor = primitive.attributes.get("NORMAL");
        // Without normals, the triangles are needed to compute them.
        let keep = options.keep_triangles || normal_accessor.is_none();
        let (triangles, incomplete_triangle) =
            self.triangles(primitive, at, n, mirrored, keep, budget)?;

        let (normals, normals_computed) = match normal_accessor {
            Some(&accessor) => {
                let normal_at = format!("{attributes_at}/NORMAL");
                // A singular matrix has no inverse: its normals are zero.
                let normal_matrix = if determinant != 0.0 && determinant.is_finite() {
                    linear.inverse().transpose()
                } else {
                    DMat3::ZERO
                };
                let normals = self.vec3s(accessor, &normal_at, n, |n| {
                    let n = normal_matrix * DVec3::from_array(n.map(f64::from));
                    if options.normalize_normals {
                        n.normalize_or_zero()
                    } else {
                        n
                    }
                })?;
                if normals.len() != n {
                    return Err(Error::invalid(
                        normal_at,
                        format!("{} normals for {n} positions", normals.len()),
                    ));
                }
                (normals, false)
            }
            None => (smooth_normals(&positions, &triangles), true),
        };
        Ok(Instance {
            node,
            mesh,
            primitive: p,
            material: primitive.material,
            positions,
            normals,
            triangles,
            normals_computed,
            incomplete_triangle,
        })
    }

    /// The primitive's triangles: from its indices (each checked against
    /// the `vertices`) or its vertices in threes, empty unless `keep`; and
    /// whether one or two vertices (or indices) are left over past them.
    fn triangles(
        &self,
        primitive: &schema::Primitive,
        at: &str,
        vertices: usize,
        mirrored: bool,
        keep: bool,
        budget: &Budget,
    ) -> Result<(Vec<[u32; 3]>, bool)> {
        let wind = |a: u32, b: u32, c: u32| if mirrored { [a, c, b] } else { [a, b, c] };
        let Some(accessor) = primitive.indices else {
            let t = if keep { (vertices / 3) as u32 } else { 0 };
            let triangles = (0..t).map(|t| wind(3 * t, 3 * t + 1, 3 * t + 2)).collect();
            return Ok((triangles, !vertices.is_multiple_of(3)));
        };
        let indices_at = format!("{at}/indices");
        let max_count = budget.triangles.saturating_mul(3);
        // Checked without being kept where they are not needed.
        let (count, max) = self.unsigned_count_max(accessor, &indices_at, max_count)?;
        let incomplete = !count.is_multiple_of(3);
        if count / 3 > budget.triangles {
            return Err(Error::over_limit(
                indices_at,
                format!(
                    "{} more triangles, past the limit of {TRIANGLES_PER_VERTEX} per placed \
                     vertex allowed",
                    count / 3
                ),
            ));
        }
        if max as usize >= vertices {
            let indices = self.unsigned(accessor, &indices_at, max_count)?;
            let k = indices
                .iter()
                .position(|&i| i == max)
                .expect("the largest is there");
            return Err(Error::invalid(
                indices_at,
                format!("index {k} is {max}, past the primitive's {vertices} vertices"),
            ));
        }
        if !keep {
            return Ok((Vec::new(), incomplete));
        }
        let indices = self.unsigned(accessor, &indices_at, max_count)?;
        let triangles = indices
            .par_chunks_exact(3)
            .with_min_len(TASK_VERTICES)
            .map(|t| wind(t[0], t[1], t[2]))
            .collect();
        Ok((triangles, incomplete))
    }
}

/// Vertices per rayon task: fewer are placed on one thread.
const TASK_VERTICES: usize = 16 * 1024;

/// What is left of the vertex limit for one primitive.
struct Budget {
    vertices: usize,
    triangles: usize,
    max_vertices: usize,
}

/// A node's matrix: `matrix`, or translation · rotation · scale.
fn local_matrix(node: &Node, at: &str) -> Result<DMat4> {
    let finite = |values: &[f64], field: &str| match values.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(i) => Err(Error::invalid(
            format!("{at}/{field}/{i}"),
            "numbers must be finite",
        )),
    };
    if let Some(m) = &node.matrix {
        finite(m, "matrix")?;
        return Ok(DMat4::from_cols_array(m));
    }
    let translation = node.translation.unwrap_or([0.0; 3]);
    let rotation = node.rotation.unwrap_or([0.0, 0.0, 0.0, 1.0]);
    let scale = node.scale.unwrap_or([1.0; 3]);
    finite(&translation, "translation")?;
    finite(&rotation, "rotation")?;
    finite(&scale, "scale")?;
    let q = DQuat::from_array(rotation);
    let length = q.length();
    // glTF asks for unit quaternions; one of another length is normalised,
    // a zero one has no rotation to give.
    if length == 0.0 {
        return Err(Error::invalid(
            format!("{at}/rotation"),
            "a zero quaternion is no rotation",
        ));
    }
    Ok(DMat4::from_scale_rotation_translation(
        DVec3::from_array(scale),
        q / length,
        DVec3::from_array(translation),
    ))
}

/// Smooth normals: at each vertex the sum of its triangles' normals
/// weighted by their areas (the cross product of two edges is twice the
/// area along the normal), normalised. A vertex of no triangle, or of
/// degenerate ones only, gets zero.
pub fn smooth_normals(positions: &[DVec3], triangles: &[[u32; 3]]) -> Vec<DVec3> {
    let mut sums = vec![DVec3::ZERO; positions.len()];
    for &[a, b, c] in triangles {
        let [pa, pb, pc] = [a, b, c].map(|i| positions[i as usize]);
        let weighted = (pb - pa).cross(pc - pa);
        for i in [a, b, c] {
            sums[i as usize] += weighted;
        }
    }
    sums.into_iter().map(DVec3::normalize_or_zero).collect()
}
