//! The f32 evaluator behind the `accurate` and `fast` precisions.
//!
//! A [`Kernel`] is a [`LightSet`] prepared once per request: each light's
//! f32 form (the spot factor of a light at infinity, the cone's cosines) is
//! computed in f64 and rounded once. A material is prepared apart, as
//! [`MaterialProducts`]: its colours times each light's (`a_cm·a_cli`,
//! `d_cm·d_cli`, `s_cm·s_cli`) and `e_cm + a_cm·a_cs`, so that a render
//! with many materials prepares its lights once, as Mesa prepares each light
//! once per state change and the material's products apart.
//!
//! Positions are recentred on a centre chosen by the caller's points (the
//! middle of their bounding box: the batch for `/v1/shade`, the scene for a
//! render) before they become f32, so that a vertex and a light 1 unit apart
//! near (1e7, 1e7, 1e7) keep their direction; normals are scaled in f64 by
//! a power of two to a length near 1 before they become f32 (lengths of
//! 1e-300 or 1e300 have no f32 form). [`Kernel::prepare`] converts a batch
//! into [`Vertices`], [`Kernel::light`] lights it.
//!
//! # How a batch is lit
//!
//! Vertices go in blocks of [`block::BLOCK`], held as structure of arrays
//! ([`block`]), with the light loop outside and the vertex loop inside so
//! that the compiler vectorises the vertex loop: 16 lanes where the CPU has
//! AVX-512, 8 with AVX2 and FMA, chosen at run time ([`task`]). A CPU
//! without FMA gets the baseline build, correct but slow: each `mul_add` of
//! the polynomials is a library call there. The square roots and divisions
//! of a block are passes of their own, so that AVX-512 can take them from
//! its estimates ([`isa`]), and whole powers of a cosine are multiplications
//! ([`power`]).
//! The fast tier lights a block from a light at a point without
//! normalising `VP_pli` where its bound allows ([`fast_point`]).
//!
//! Like Mesa's fixed-function pipeline, which builds its vertex program from
//! a key of the enabled state, the evaluator is specialised once per scene:
//! its [`StateKey`] picks a monomorphised task function ([`variant`]), and
//! each light picks its own loop ([`directional`], [`positional`] with or
//! without attenuation and cone), so no vertex loop branches on a scene
//! feature. A scene with one directional light and no specular runs one
//! multiply-add loop per colour channel, and never reads the positions.
//! The colours are clamped as they are interleaved ([`store`]).
//!
//! The documented error bounds hold where the equation is continuous. It
//! has two steps: the edge of a spot cone and, with shininess 0, `f_i` at
//! `n·VP = 0`. A vertex within about 1e-7 (the f32 rounding of its
//! direction) of a step can land on the other side of it than the f64
//! reference puts it; both tiers compute `VP_pli` and the cone test to full
//! f32 accuracy so that this stays that rare.

// The vertex loops index several arrays of one block by lane on purpose:
// that is the structure of arrays the vectoriser needs.
#![allow(clippy::needless_range_loop)]

mod block;
mod directional;
mod fast_point;
mod instruction_set;
mod isa;
mod light;
mod point_pass;
mod positional;
mod power;
mod range;
mod specular;
mod store;
mod task;
mod variant;
mod vertices;

pub use instruction_set::{ISA_VARIABLE, InstructionSet};
pub use task::TASK_VERTICES;
pub use vertices::Vertices;

use glam::{DVec3, DVec4, Vec3, Vec4};

use super::fastmath::Powers;
use super::{
    ColorControl, LightPosition, LightSet, Material, SpecularModel, SurfaceMaterial, Viewer,
    unit_or_zero,
};

/// How the f32 tiers compute `pow`, whole powers and `1/x`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tier {
    Accurate,
    Fast,
}

/// The features of a scene that change the shape of the vertex loop.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StateKey {
    pub local_viewer: bool,
    /// Some light has a non-zero specular product on some side.
    pub specular: bool,
    pub phong: bool,
    /// Normals used as given (GL_NORMALIZE off): the specular base is then
    /// not a cosine.
    pub raw_normals: bool,
}

/// A light set prepared for f32 evaluation: built once per request, shared
/// by every material.
#[derive(Clone, Debug)]
pub struct Kernel {
    centre: DVec3,
    sources: Vec<Source>,
    /// Per light, in f64 for the material products: `a_cli`, `d_cli`, `s_cli`.
    light_colors: Vec<[DVec4; 3]>,
    /// `a_cs`.
    global_ambient: DVec4,
    /// Recentred eye point or unit direction.
    viewer: Viewer32,
    normalize: bool,
    two_side: bool,
    specular_model: SpecularModel,
    color_control: ColorControl,
    attenuation_clamp: bool,
    /// See [`LightSet::depends_on_position`]; when false the positions are
    /// never read.
    depends_on_position: bool,
}

/// The f32 form of one light.
#[derive(Clone, Copy, Debug)]
enum Source {
    /// Unit vector towards the light, and its spot factor (constant for a
    /// light at infinity).
    Directional {
        vp_pli: Vec3,
        spot: f32,
        /// `ĥ` for an infinite viewer (unused for a local one).
        half: Vec3,
    },
    Positional {
        /// Recentred position.
        p_pli: Vec3,
        k: [f32; 3],
        cone: Option<Cone>,
    },
}

#[derive(Clone, Copy, Debug)]
struct Cone {
    direction: Vec3,
    /// `1/|direction|²`: 1 within f32 rounding.
    inverse_direction2: f32,
    exponent: Powers,
    /// In f64 for the exact test of the vertices near the edge (the f32
    /// tests read only its sign).
    cos_cutoff: f64,
    /// The cone is tested on `sin²` up to a cutoff of [`NARROW_CONE_CUTOFF`]
    /// (f32 holds it without cancellation near the axis, so a cutoff of 0
    /// lights its axis) and on `cos²` above (well conditioned near 90°, and
    /// a cutoff of exactly 90° passes every point in front of the light).
    narrow: bool,
    sin2_cutoff: f32,
    cos2_cutoff: f32,
    /// A cutoff of at least [`COS2_CONE_CUTOFF`] and an exponent of at most
    /// [`MAX_COS2_CONE_EXPONENT`]: where [`super::fastmath::Math::CONE_FROM_COS2`]
    /// says so, the cone is tested on `cos²` and its power raised from it.
    from_cos2: bool,
}

/// The largest cutoff, in degrees, of a cone tested on `sin²`.
const NARROW_CONE_CUTOFF: f64 = 45.0;

/// The smallest cutoff, in degrees, of a cone that the fast tier tests on
/// `cos²` alone. A block with a vertex near the edge takes the exact test
/// (see [`positional`]), which the band of a narrower cone, wider in angle,
/// would ask for too often.
const COS2_CONE_CUTOFF: f64 = 30.0;

/// The largest spot exponent whose power the fast tier raises from `cos²`
/// alone: GL's own largest, whose error is a few ULP times 64.
const MAX_COS2_CONE_EXPONENT: f64 = 128.0;

#[derive(Clone, Copy, Debug)]
enum Viewer32 {
    Local(Vec3),
    Infinite(Vec3),
}

/// A material prepared for one [`Kernel`]: its colours times each light's.
#[derive(Clone, Debug)]
pub struct MaterialProducts {
    front: SideProducts,
    /// Only when the light model is two-sided.
    back: Option<SideProducts>,
}

/// One side's material, premultiplied by each light's colours.
#[derive(Clone, Debug)]
struct SideProducts {
    /// `e_cm + a_cm·a_cs`
    base: Vec3,
    alpha: f32,
    shininess: f32,
    /// The specular power's plan in each tier.
    shininess_power: Powers,
    /// Per light: `a_cm·a_cli`, `d_cm·d_cli`, `s_cm·s_cli`.
    products: Vec<[Vec3; 3]>,
}

/// Colours of a batch: front, and back when the model is two-sided.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Colors {
    pub front: Vec<Vec4>,
    pub back: Option<Vec<Vec4>>,
}

impl Kernel {
    /// Prepares `lights` for the vertices `positions` (used only to choose
    /// the centre, and only when lighting depends on positions).
    pub fn new(lights: &LightSet, positions: &[DVec3]) -> Self {
        let depends_on_position = lights.depends_on_position();
        let centre = if depends_on_position {
            bounding_box_centre(positions)
        } else {
            DVec3::ZERO
        };
        let at = |p: DVec3| (p - centre).as_vec3();
        let sources = lights
            .lights()
            .iter()
            .map(|l| match l.position {
                LightPosition::Directional(vp_pli) => Source::Directional {
                    vp_pli: vp_pli.as_vec3(),
                    // `P_pli V` is the same for every vertex: the negated direction.
                    spot: l.spot.factor(-vp_pli) as f32,
                    half: match lights.viewer {
                        Viewer::Infinite(dir) => unit_or_zero(vp_pli + dir).as_vec3(),
                        Viewer::Local(_) => Vec3::ZERO,
                    },
                },
                LightPosition::Positional(p) => Source::Positional {
                    p_pli: at(p),
                    k: l.attenuation.map(|k| k as f32),
                    cone: l.spot.is_cone().then(|| Cone::new(&l.spot)),
                },
            })
            .collect();
        let model = &lights.model;
        Self {
            centre,
            sources,
            light_colors: lights
                .lights()
                .iter()
                .map(|l| [l.ambient, l.diffuse, l.specular])
                .collect(),
            global_ambient: model.ambient,
            viewer: match lights.viewer {
                Viewer::Local(eye) => Viewer32::Local(at(eye)),
                Viewer::Infinite(dir) => Viewer32::Infinite(dir.as_vec3()),
            },
            normalize: model.normalize_normals,
            two_side: model.two_side,
            specular_model: model.specular_model,
            color_control: model.color_control,
            attenuation_clamp: model.attenuation_clamp,
            depends_on_position,
        }
    }

    /// Prepares `material` for these lights: per light and side, its colours
    /// times the light's.
    pub fn products(&self, material: &SurfaceMaterial) -> MaterialProducts {
        MaterialProducts {
            front: self.side_products(&material.front),
            back: self.two_side.then(|| self.side_products(&material.back)),
        }
    }

    fn side_products(&self, m: &Material) -> SideProducts {
        let rgb = |c: DVec4| c.truncate().as_vec3();
        SideProducts {
            base: rgb(m.emission + m.ambient * self.global_ambient),
            alpha: m.diffuse.w.clamp(0.0, 1.0) as f32,
            shininess: m.shininess as f32,
            shininess_power: Powers::new(m.shininess as f32),
            products: self
                .light_colors
                .iter()
                .map(|[ambient, diffuse, specular]| {
                    [
                        rgb(m.ambient * *ambient),
                        rgb(m.diffuse * *diffuse),
                        rgb(m.specular * *specular),
                    ]
                })
                .collect(),
        }
    }

    /// The state key of these lights on `material`.
    pub fn state_key(&self, material: &MaterialProducts) -> StateKey {
        let sides = std::iter::once(&material.front).chain(material.back.as_ref());
        StateKey {
            local_viewer: matches!(self.viewer, Viewer32::Local(_)),
            specular: sides
                .flat_map(|s| s.products.iter())
                .any(|[_, _, specular]| *specular != Vec3::ZERO),
            phong: self.specular_model == SpecularModel::Phong,
            raw_normals: !self.normalize,
        }
    }

    /// The specular terms are summed and clamped on their own (else they go
    /// into the primary colour).
    fn separate_specular(&self) -> bool {
        self.color_control == ColorControl::SeparateSpecular
    }
}

impl Cone {
    fn new(spot: &super::Spot) -> Self {
        let direction = spot.direction.as_vec3();
        Self {
            direction,
            inverse_direction2: 1.0 / direction.length_squared(),
            exponent: Powers::new(spot.exponent as f32),
            cos_cutoff: spot.cos_cutoff(),
            narrow: spot.cutoff <= NARROW_CONE_CUTOFF,
            sin2_cutoff: round_down(spot.cutoff.to_radians().sin().powi(2)),
            cos2_cutoff: round_up(spot.cos_cutoff().powi(2)),
            from_cos2: spot.cutoff >= COS2_CONE_CUTOFF && spot.exponent <= MAX_COS2_CONE_EXPONENT,
        }
    }
}

/// The largest f32 at most `x`: an f32 `y` is `<= x` exactly where it is
/// `<=` this, so that the cone test's bound does not move its edge.
fn round_down(x: f64) -> f32 {
    let y = x as f32;
    if f64::from(y) > x { y.next_down() } else { y }
}

/// The smallest f32 at least `x`: an f32 `y` is `>= x` exactly where it is
/// `>=` this.
fn round_up(x: f64) -> f32 {
    let y = x as f32;
    if f64::from(y) < x { y.next_up() } else { y }
}

/// The middle of the bounding box of `points` (zero for none).
fn bounding_box_centre(points: &[DVec3]) -> DVec3 {
    let (lo, hi) = points
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        });
    if points.is_empty() {
        DVec3::ZERO
    } else {
        (lo + hi) * 0.5
    }
}
