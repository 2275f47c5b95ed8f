//! What one pass evaluates, prepared once: the lights' geometry, each
//! material side's products, and for each model (GL, a deviation, a pair of
//! them) which factors of which light it changes.
//!
//! A light's contribution is `sa·A + sd·D + ss·S`, with the products
//! `A = a_cm·a_cli`, `D = d_cm·d_cli`, `S = s_cm·s_cli` and the scalars
//! `sa = att·spot`, `sd = att·spot·(n⊙VP)`, `ss = att·spot·f·(n⊙ĥ)^s`. A
//! deviation changes some factors of some lights: the attenuation, the
//! spot factor, the diffuse base, the gate `f` or the specular power. Each
//! distinct changed factor is a *variant*, computed once per block and
//! light however many models read it, and a model adds, for each light it
//! changes, only the difference of the scalars it changes. Deviations that
//! act on the constant terms or on the output need no light at all.

use glam::{DVec3, DVec4};
use glint_lighting::deviation::{CLAMPED_EXPONENT, Deviation, Deviations};
use glint_lighting::reference::{Port, spot_factor};
use glint_lighting::{
    ColorControl, Light, LightPosition, LightSet, Material, SpecularModel, SurfaceMaterial, Viewer,
};

use super::arith::{Arith, Real};
use num_traits::Float;

/// A colour or a product, RGBA.
pub(crate) type Rgba<F> = [F; 4];

/// The scene of a pass: what lights it and what the surfaces are made of.
pub(crate) struct PassScene<'a> {
    pub lights: &'a LightSet,
    pub swapped_viewer: Viewer,
    /// The materials; a point names one by index.
    pub materials: &'a [SurfaceMaterial],
    /// Where the positions are recentred (see [`super::Points`]).
    pub centre: DVec3,
    /// Some normal is not of unit length, so that a port that does not
    /// normalise them draws something else.
    pub unnormalized_normals: bool,
    /// Alpha is compared: the deviations that change alpha alone count.
    pub alpha: bool,
    /// Back colours are compared.
    pub back: bool,
}

/// The viewer as the lanes read it.
#[derive(Clone, Copy, Debug)]
pub(crate) enum ViewerPlan<F> {
    /// A recentred eye point: `VP_e` per lane.
    Local([F; 3]),
    Infinite([F; 3]),
}

/// A light's geometry, the same on both sides.
#[derive(Clone, Debug)]
pub(crate) struct LightPlan<A: Arith> {
    pub source: Source<A::F>,
    /// GL's spot factor where it is the same for every vertex (a light at
    /// infinity; 1 without a cone).
    pub spot: A::F,
    pub cone: Option<ConePlan<A>>,
    /// The spot factors the models read in place of GL's, and the
    /// deviations that make each.
    pub spot_variants: Vec<SpotVariant<A>>,
    pub spot_keys: Vec<Deviations>,
}

#[derive(Clone, Copy, Debug)]
pub(crate) enum Source<F> {
    /// `VP_pli`.
    Directional([F; 3]),
    Positional {
        /// Recentred.
        p: [F; 3],
        k: [F; 3],
        /// The coefficients are not (1, 0, 0).
        attenuated: bool,
        /// `att = min(att, 1)`.
        clamp: bool,
    },
}

/// A spotlight's cone at a point.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ConePlan<A: Arith> {
    /// `ŝ_dli`, and `1/|ŝ_dli|²` (1 but for rounding).
    pub direction: [A::F; 3],
    pub inverse_direction2: A::F,
    pub cos_cutoff: A::F,
    pub power: SpotPower<A>,
}

/// How the power of a spot cosine is taken.
#[derive(Clone, Copy, Debug)]
pub(crate) enum SpotPower<A: Arith> {
    /// By the tier's plan of the exponent.
    Plan(A::Plan),
    /// An exponent of 0 with `0^0 = 0`: 1 where the cosine is above 0.
    Positive,
}

impl<A: Arith> PartialEq for SpotPower<A> {
    fn eq(&self, other: &Self) -> bool {
        match (self, other) {
            (SpotPower::Plan(a), SpotPower::Plan(b)) => a == b,
            (SpotPower::Positive, SpotPower::Positive) => true,
            _ => false,
        }
    }
}

/// A spot factor other than GL's.
#[derive(Clone, Copy, Debug)]
pub(crate) enum SpotVariant<A: Arith> {
    /// The same for every vertex (a light at infinity).
    Constant(A::F),
    /// A cone with another cutoff or power.
    Cone {
        cos_cutoff: A::F,
        power: SpotPower<A>,
    },
}

/// Which specular power a variant takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct PowerKey {
    pub phong: bool,
    pub swapped_viewer: bool,
    pub half_unnormalized: bool,
    /// The normal's own length (a port that does not normalise).
    pub raw: bool,
    pub clamped: bool,
    pub zero_power_zero: bool,
}

impl PowerKey {
    /// GL's own power.
    pub const GL: PowerKey = PowerKey {
        phong: false,
        swapped_viewer: false,
        half_unnormalized: false,
        raw: false,
        clamped: false,
        zero_power_zero: false,
    };
}

/// A specular power, ready for the lanes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PowerPlan<A: Arith> {
    pub key: PowerKey,
    pub specular_model: SpecularModel,
    /// The exponent, for bases that are not cosines.
    pub exponent: A::F,
    /// Its plan, for cosines.
    pub plan: A::Plan,
    /// `0^0 = 0` applies: the exponent is 0 and the port takes it so.
    pub zero_power_zero: bool,
}

/// Which diffuse base a variant takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct DiffuseKey {
    pub unclamped: bool,
    pub raw: bool,
}

/// One side of one material: its colours times each light's.
#[derive(Clone, Debug)]
pub(crate) struct SidePlan<A: Arith> {
    /// `e_cm + a_cm·a_cs`.
    pub base: Rgba<A::F>,
    /// The diffuse alpha, clamped, and as given.
    pub alpha: A::F,
    pub raw_alpha: A::F,
    /// GL's specular power.
    pub power: PowerPlan<A>,
    pub lights: Vec<SideLight<A>>,
    /// Per model: the base it starts from, and whether it changes some
    /// light's terms.
    pub model_bases: Vec<Rgba<A::F>>,
    pub model_touches: Vec<bool>,
}

/// One light's products on one side, and what each model changes of it.
#[derive(Clone, Debug)]
pub(crate) struct SideLight<A: Arith> {
    pub ambient: Rgba<A::F>,
    pub diffuse: Rgba<A::F>,
    pub specular: Rgba<A::F>,
    /// The largest magnitude of a channel of each product.
    pub magnitudes: [A::F; 3],
    pub power_variants: Vec<PowerPlan<A>>,
    pub diffuse_variants: Vec<DiffuseKey>,
    /// Per model: `None` where it takes GL's terms.
    pub models: Vec<Option<ModelLight>>,
}

/// What a model changes of one light's terms.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct ModelLight {
    /// `att = 1`.
    pub attenuation_one: bool,
    /// An index into the light's spot variants.
    pub spot: Option<usize>,
    /// The ambient term takes `att` alone.
    pub ambient_unspotted: bool,
    pub ambient_off: bool,
    /// An index into the side's diffuse variants.
    pub diffuse: Option<usize>,
    pub ungated: bool,
    /// An index into the side's power variants.
    pub power: Option<usize>,
    /// Which of the three terms differ from GL's.
    pub ambient_term: bool,
    pub diffuse_term: bool,
    pub specular_term: bool,
}

/// How a model writes its colour.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ModelPlan {
    /// The specular sum clamped on its own.
    pub separate: bool,
    pub clamp: bool,
    pub srgb: bool,
    /// The back colour is the front colour.
    pub front_for_back: bool,
    pub alpha_summed: bool,
}

/// Everything a pass evaluates.
#[derive(Clone, Debug)]
pub(crate) struct Pass<A: Arith> {
    pub models: Vec<ModelPlan>,
    pub lights: Vec<LightPlan<A>>,
    /// Per material, its front side and its back side.
    pub sides: Vec<[SidePlan<A>; 2]>,
    pub viewer: ViewerPlan<A::F>,
    /// The viewer of the other kind, where some model reads it.
    pub swapped_viewer: Option<ViewerPlan<A::F>>,
    /// GL_NORMALIZE: the lanes hold unit normals (else as given).
    pub normalize: bool,
    /// Some model reads the normals' own lengths.
    pub raw_lengths: bool,
    /// The scene's specular colour is separate.
    pub separate: bool,
    /// Some model sums alpha.
    pub alpha_sums: bool,
    /// The lanes need positions.
    pub positions: bool,
    /// A block whose GL terms reach this size is evaluated again with each
    /// model summing its own terms: taking a term this large away from
    /// GL's sum would leave more than an eighth of the tier's bound.
    pub direct_above: A::F,
}

impl<A: Arith> Pass<A> {
    /// The pass of `models` (the first is GL, the empty set) over `scene`.
    pub fn new(scene: &PassScene, models: &[Deviations]) -> Self {
        let lights = scene.lights;
        let model = &lights.model;
        let f = |x: f64| A::F::of(x);
        let at = |p: DVec3| (p - scene.centre).to_array().map(f);
        let viewer_plan = |v: Viewer| match v {
            Viewer::Local(eye) => ViewerPlan::Local(at(eye)),
            Viewer::Infinite(d) => ViewerPlan::Infinite(d.to_array().map(f)),
        };
        let swaps = models.iter().any(|d| d.contains(Deviation::ViewerSwapped));
        let separate = model.color_control == ColorControl::SeparateSpecular;
        let model_plans: Vec<ModelPlan> = models
            .iter()
            .map(|&deviations| ModelPlan {
                separate: separate && !deviations.contains(Deviation::SeparateSpecularIgnored),
                clamp: !deviations.contains(Deviation::UnclampedOutput),
                srgb: deviations.contains(Deviation::SrgbEncoded),
                front_for_back: deviations.contains(Deviation::TwoSideIgnored),
                alpha_summed: deviations.contains(Deviation::AlphaSummed),
            })
            .collect();
        let light_plans: Vec<LightPlan<A>> = lights
            .lights()
            .iter()
            .map(|l| light_plan::<A>(l, model.attenuation_clamp, models, &at))
            .collect();
        let sides = scene
            .materials
            .iter()
            .map(|m| [&m.front, &m.back].map(|side| side_plan(scene, side, models, &light_plans)))
            .collect();
        let uses_position = |v: Viewer| matches!(v, Viewer::Local(_));
        Self {
            raw_lengths: models
                .iter()
                .any(|d| raw_normals(scene, *d) && !d.is_empty()),
            alpha_sums: model_plans.iter().any(|m| m.alpha_summed),
            positions: lights.depends_on_position()
                || (swaps && uses_position(scene.swapped_viewer)),
            models: model_plans,
            lights: light_plans,
            sides,
            viewer: viewer_plan(lights.viewer),
            swapped_viewer: swaps.then(|| viewer_plan(scene.swapped_viewer)),
            normalize: model.normalize_normals,
            separate,
            direct_above: A::F::of(A::PRECISION.max_abs_error() / (8.0 * A::F::epsilon().wide())),
        }
    }
}

/// A port with `deviations` reads the normals' own lengths where GL
/// normalises them.
fn raw_normals(scene: &PassScene, deviations: Deviations) -> bool {
    deviations.contains(Deviation::NormalsUnnormalized)
        && scene.lights.model.normalize_normals
        && scene.unnormalized_normals
}

fn light_plan<A: Arith>(
    light: &Light,
    attenuation_clamp: bool,
    models: &[Deviations],
    at: &impl Fn(DVec3) -> [A::F; 3],
) -> LightPlan<A> {
    let f = |x: f64| A::F::of(x);
    let spot = &light.spot;
    let gl_spot_power = |exponent: f64, zero_power_zero: bool| {
        if exponent == 0.0 && zero_power_zero {
            SpotPower::Positive
        } else {
            SpotPower::Plan(A::plan(exponent))
        }
    };
    let (source, gl_spot, cone) = match light.position {
        LightPosition::Directional(vp) => {
            let spot = spot_factor(&port(Deviations::NONE), light, -vp);
            (Source::Directional(vp.to_array().map(f)), f(spot), None)
        }
        LightPosition::Positional(p) => (
            Source::Positional {
                p: at(p),
                k: light.attenuation.map(f),
                attenuated: light.attenuation != [1.0, 0.0, 0.0],
                clamp: attenuation_clamp,
            },
            f(1.0),
            spot.is_cone().then(|| ConePlan {
                direction: spot.direction.to_array().map(f),
                inverse_direction2: f(1.0 / spot.direction.length_squared()),
                cos_cutoff: f(spot.cos_cutoff()),
                power: gl_spot_power(spot.exponent, false),
            }),
        ),
    };
    let mut plan = LightPlan {
        source,
        spot: gl_spot,
        cone,
        spot_variants: Vec::new(),
        spot_keys: Vec::new(),
    };
    // The variants, each once, in the order the models first ask for them.
    for &d in models {
        if let Some(key) = spot_key(light, d)
            && !plan.spot_keys.contains(&key)
        {
            plan.spot_keys.push(key);
            plan.spot_variants.push(match light.position {
                LightPosition::Directional(vp) => {
                    SpotVariant::Constant(f(spot_factor(&port(key), light, -vp)))
                }
                LightPosition::Positional(_) => SpotVariant::Cone {
                    cos_cutoff: f(if key.contains(Deviation::SpotCutoffRadians) {
                        spot.cutoff.cos()
                    } else {
                        spot.cos_cutoff()
                    }),
                    power: gl_spot_power(
                        spot_exponent(light, key),
                        key.contains(Deviation::ZeroPowerZero),
                    ),
                },
            });
        }
    }
    plan
}

/// A port of `deviations` alone; its swapped viewer is never read here.
fn port(deviations: Deviations) -> Port {
    Port {
        deviations,
        swapped_viewer: Viewer::Infinite(DVec3::Z),
    }
}

/// The spot exponent a port of `deviations` uses.
fn spot_exponent(light: &Light, deviations: Deviations) -> f64 {
    if deviations.contains(Deviation::SpotExponentIgnored) {
        0.0
    } else if deviations.contains(Deviation::ExponentsClamped) {
        light.spot.exponent.min(CLAMPED_EXPONENT)
    } else {
        light.spot.exponent
    }
}

/// The deviations of `deviations` that change this light's spot factor
/// (none: GL's factor).
fn spot_key(light: &Light, deviations: Deviations) -> Option<Deviations> {
    let spot = &light.spot;
    if !spot.is_cone() {
        return None;
    }
    let directional = matches!(light.position, LightPosition::Directional(_));
    let mut key = Deviations::NONE;
    if directional && deviations.contains(Deviation::DirectionalSpotIgnored) {
        return Some(key.with(Deviation::DirectionalSpotIgnored));
    }
    if deviations.contains(Deviation::SpotCutoffRadians) {
        key = key.with(Deviation::SpotCutoffRadians);
    }
    if deviations.contains(Deviation::SpotExponentIgnored) && spot.exponent != 0.0 {
        key = key.with(Deviation::SpotExponentIgnored);
    }
    if deviations.contains(Deviation::ExponentsClamped) && spot.exponent > CLAMPED_EXPONENT {
        key = key.with(Deviation::ExponentsClamped);
    }
    // 0^0 matters only with an exponent of 0, where the cosine can be 0 inside the
    // cone: a cutoff of 90°.
    if deviations.contains(Deviation::ZeroPowerZero)
        && spot_exponent(light, key) == 0.0
        && spot.cos_cutoff() <= 0.0
    {
        key = key.with(Deviation::ZeroPowerZero);
    }
    (!key.is_empty()).then_some(key)
}

fn side_plan<A: Arith>(
    scene: &PassScene,
    material: &Material,
    models: &[Deviations],
    light_plans: &[LightPlan<A>],
) -> SidePlan<A> {
    let lights = scene.lights;
    let model = &lights.model;
    let f = |x: f64| A::F::of(x);
    let rgba = |c: DVec4| c.to_array().map(f);
    let gl_power = power_plan::<A>(scene, material, PowerKey::GL);
    let light_sides = lights
        .lights()
        .iter()
        .zip(light_plans)
        .map(|(light, plan)| {
            let products = [
                material.ambient * light.ambient,
                material.diffuse * light.diffuse,
                material.specular * light.specular,
            ];
            let mut side = SideLight {
                ambient: rgba(products[0]),
                diffuse: rgba(products[1]),
                specular: rgba(products[2]),
                magnitudes: products.map(|p| f(p.abs().max_element())),
                power_variants: Vec::new(),
                diffuse_variants: Vec::new(),
                models: Vec::new(),
            };
            for (index, &d) in models.iter().enumerate() {
                let changed = if index == 0 {
                    None
                } else {
                    model_light(scene, material, light, plan, d, &mut side)
                };
                side.models.push(changed);
            }
            side
        })
        .collect::<Vec<_>>();
    let base_of = |d: Deviations| {
        let emission = if d.contains(Deviation::EmissionMissing) {
            DVec4::ZERO
        } else {
            material.emission
        };
        let global = if d.contains(Deviation::GlobalAmbientMissing) {
            DVec4::ZERO
        } else {
            material.ambient * model.ambient
        };
        rgba(emission + global)
    };
    SidePlan {
        base: base_of(Deviations::NONE),
        alpha: f(material.diffuse.w.clamp(0.0, 1.0)),
        raw_alpha: f(material.diffuse.w),
        power: gl_power,
        model_bases: models.iter().map(|&d| base_of(d)).collect(),
        model_touches: (0..models.len())
            .map(|m| light_sides.iter().any(|l| l.models[m].is_some()))
            .collect(),
        lights: light_sides,
    }
}

/// The specular power of `key` on `material`.
fn power_plan<A: Arith>(scene: &PassScene, material: &Material, key: PowerKey) -> PowerPlan<A> {
    let s = if key.clamped {
        material.shininess.min(CLAMPED_EXPONENT)
    } else {
        material.shininess
    };
    PowerPlan {
        key,
        specular_model: if key.phong {
            SpecularModel::Phong
        } else {
            scene.lights.model.specular_model
        },
        exponent: A::F::of(s),
        plan: A::plan(s),
        zero_power_zero: key.zero_power_zero && s == 0.0,
    }
}

/// What the model of `d` changes of `light`'s terms on this side, with the
/// variants it reads added to `side` (and to the light's plan): `None`
/// where its terms are GL's.
fn model_light<A: Arith>(
    scene: &PassScene,
    material: &Material,
    light: &Light,
    plan: &LightPlan<A>,
    d: Deviations,
    side: &mut SideLight<A>,
) -> Option<ModelLight> {
    let nonzero = |c: &Rgba<A::F>| {
        let channels = if scene.alpha { 4 } else { 3 };
        c[..channels].iter().any(|x| x.wide() != 0.0)
    };
    let (has_ambient, has_diffuse, has_specular) = (
        nonzero(&side.ambient),
        nonzero(&side.diffuse),
        nonzero(&side.specular),
    );
    let positional = matches!(light.position, LightPosition::Positional(_));
    let cone = light.spot.is_cone();
    let spot = spot_key(light, d).map(|key| {
        plan.spot_keys
            .iter()
            .position(|k| *k == key)
            .expect("the light's plan holds a variant for every model's key")
    });
    let raw = raw_normals(scene, d);
    let diffuse_key = DiffuseKey {
        unclamped: d.contains(Deviation::DiffuseUnclamped),
        raw,
    };
    let diffuse = (diffuse_key.unclamped || diffuse_key.raw).then(|| {
        index_of(&mut side.diffuse_variants, diffuse_key, |k| {
            *k == diffuse_key
        })
    });
    let blinn = scene.lights.model.specular_model == SpecularModel::BlinnPhong;
    let phong = d.contains(Deviation::PhongSpecular) && blinn;
    let power_key = PowerKey {
        phong,
        swapped_viewer: d.contains(Deviation::ViewerSwapped),
        half_unnormalized: d.contains(Deviation::HalfVectorUnnormalized) && blinn && !phong,
        raw,
        clamped: d.contains(Deviation::ExponentsClamped) && material.shininess > CLAMPED_EXPONENT,
        zero_power_zero: d.contains(Deviation::ZeroPowerZero) && material.shininess == 0.0,
    };
    let power = (power_key != PowerKey::GL).then(|| {
        let plan = power_plan::<A>(scene, material, power_key);
        index_of(&mut side.power_variants, plan, |p| p.key == power_key)
    });
    let changed = ModelLight {
        attenuation_one: d.contains(Deviation::AttenuationIgnored)
            && positional
            && light.attenuation != [1.0, 0.0, 0.0],
        spot,
        ambient_unspotted: d.contains(Deviation::AmbientSpotIgnored) && cone,
        ambient_off: d.contains(Deviation::LightAmbientMissing),
        diffuse,
        ungated: d.contains(Deviation::SpecularUngated),
        power,
        ..ModelLight::default()
    };
    let scale_changed = changed.attenuation_one || changed.spot.is_some();
    let changed = ModelLight {
        ambient_term: has_ambient
            && (changed.ambient_off
                || changed.attenuation_one
                || changed.ambient_unspotted
                || changed.spot.is_some()),
        diffuse_term: has_diffuse && (scale_changed || changed.diffuse.is_some()),
        specular_term: has_specular
            && (scale_changed || changed.ungated || changed.power.is_some()),
        ..changed
    };
    (changed.ambient_term || changed.diffuse_term || changed.specular_term).then_some(changed)
}

/// The index of the item `matches` finds in `items`, `item` pushed first if
/// there is none.
fn index_of<T>(items: &mut Vec<T>, item: T, matches: impl Fn(&T) -> bool) -> usize {
    match items.iter().position(matches) {
        Some(i) => i,
        None => {
            items.push(item);
            items.len() - 1
        }
    }
}
