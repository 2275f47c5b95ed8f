//! The f32 evaluator behind the `accurate` and `fast` precisions.
//!
//! A [`Kernel`] is built once per lighting description: material × light
//! colour products, the spot factor of directional lights and the cone cosines
//! are computed there, in f64, and rounded once. Positions are recentred on a
//! centre chosen by the caller's points (the middle of their bounding box:
//! the batch for `/v1/shade`, the scene for a render) before they become f32,
//! so that a vertex and a light 1 unit apart near (1e7, 1e7, 1e7) keep their
//! direction; normals are scaled in f64 by a power of two to a length near 1
//! before they become f32 (lengths of 1e-300 or 1e300 have no f32 form).
//!
//! [`Kernel::prepare`] converts a batch, [`Kernel::shade`] lights it (see
//! [`batch`]); the renderer lights its hits in batches too.

mod batch;
mod isa;

pub use batch::{StateKey, Tier, Vertices};

use glam::{DVec3, Vec3, Vec4};

use super::fastmath::Powers;
use super::{ColorControl, LightPosition, Lighting, Material, SpecularModel, Viewer, unit_or_zero};

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
    /// The cone is tested on `sin²` up to a cutoff of 45° (f32 holds it
    /// without cancellation near the axis, so a cutoff of 0 lights its
    /// axis) and on `cos²` above (well conditioned near 90°, and a cutoff of
    /// exactly 90° passes every point in front of the light).
    narrow: bool,
    sin2_cutoff: f32,
    cos2_cutoff: f32,
    /// A cutoff of at least [`COS2_CONE_CUTOFF`] and an exponent of at most
    /// 128, the largest of GL: where [`super::fastmath::Math::CONE_FROM_COS2`]
    /// says so, the cone is tested on `cos²` and its power raised from it.
    from_cos2: bool,
}

/// The smallest cutoff, in degrees, of a cone that the fast tier tests on
/// `cos²` alone. A block with a vertex near the edge takes the exact test
/// (see `batch`), which the band of a narrower cone, wider in angle, would
/// ask for too often.
pub(super) const COS2_CONE_CUTOFF: f64 = 30.0;

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

impl SideProducts {
    fn new(lighting: &Lighting, m: &Material) -> Self {
        let rgb = |c: glam::DVec4| c.truncate().as_vec3();
        Self {
            base: rgb(m.emission + m.ambient * lighting.model.ambient),
            alpha: m.diffuse.w.clamp(0.0, 1.0) as f32,
            shininess: m.shininess as f32,
            shininess_power: Powers::new(m.shininess as f32),
            products: lighting
                .lights
                .iter()
                .map(|l| {
                    [
                        rgb(m.ambient * l.ambient),
                        rgb(m.diffuse * l.diffuse),
                        rgb(m.specular * l.specular),
                    ]
                })
                .collect(),
        }
    }
}

/// A lighting description prepared for f32 evaluation of one batch.
#[derive(Clone, Debug)]
pub struct Kernel {
    centre: DVec3,
    sources: Vec<Source>,
    front: SideProducts,
    back: Option<SideProducts>,
    /// Recentred eye point or unit direction.
    viewer: Viewer32,
    normalize: bool,
    specular_model: SpecularModel,
    color_control: ColorControl,
    attenuation_clamp: bool,
    /// See [`Lighting::depends_on_position`]; when false the positions are
    /// never read.
    depends_on_position: bool,
}

#[derive(Clone, Copy, Debug)]
enum Viewer32 {
    Local(Vec3),
    Infinite(Vec3),
}

/// Colours of a batch: front, and back when the model is two-sided.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Colors {
    pub front: Vec<Vec4>,
    pub back: Option<Vec<Vec4>>,
}

impl Kernel {
    /// Prepares `lighting` for the vertices `positions` (used only to choose
    /// the centre, and only when lighting depends on positions).
    pub fn new(lighting: &Lighting, positions: &[DVec3]) -> Self {
        let depends_on_position = lighting.depends_on_position();
        let centre = if depends_on_position {
            bounding_box_centre(positions)
        } else {
            DVec3::ZERO
        };
        let at = |p: DVec3| (p - centre).as_vec3();
        let sources = lighting
            .lights
            .iter()
            .map(|l| match l.position {
                LightPosition::Directional(vp_pli) => Source::Directional {
                    vp_pli: vp_pli.as_vec3(),
                    // `P_pli V` is the same for every vertex: the negated direction.
                    spot: l.spot.factor(-vp_pli) as f32,
                    half: match lighting.viewer {
                        Viewer::Infinite(dir) => unit_or_zero(vp_pli + dir).as_vec3(),
                        Viewer::Local(_) => Vec3::ZERO,
                    },
                },
                LightPosition::Positional(p) => Source::Positional {
                    p_pli: at(p),
                    k: l.attenuation.map(|k| k as f32),
                    cone: l.spot.is_cone().then(|| Cone {
                        direction: l.spot.direction.as_vec3(),
                        inverse_direction2: 1.0 / l.spot.direction.as_vec3().length_squared(),
                        exponent: Powers::new(l.spot.exponent as f32),
                        cos_cutoff: l.spot.cos_cutoff(),
                        narrow: l.spot.cutoff <= 45.0,
                        sin2_cutoff: round_down(l.spot.cutoff.to_radians().sin().powi(2)),
                        cos2_cutoff: round_up(l.spot.cos_cutoff().powi(2)),
                        from_cos2: l.spot.cutoff >= COS2_CONE_CUTOFF && l.spot.exponent <= 128.0,
                    }),
                },
            })
            .collect();
        let model = &lighting.model;
        Self {
            centre,
            sources,
            front: SideProducts::new(lighting, &lighting.front),
            back: model
                .two_side
                .then(|| SideProducts::new(lighting, &lighting.back)),
            viewer: match lighting.viewer {
                Viewer::Local(eye) => Viewer32::Local(at(eye)),
                Viewer::Infinite(dir) => Viewer32::Infinite(dir.as_vec3()),
            },
            normalize: model.normalize_normals,
            specular_model: model.specular_model,
            color_control: model.color_control,
            attenuation_clamp: model.attenuation_clamp,
            depends_on_position,
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
