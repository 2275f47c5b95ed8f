//! Section 2.14.1 for one side of a block: the light loop outside, the
//! vertex loops of each light's kind inside. What a light's loops read
//! that depends on the light, the side and the tier alone (its colours,
//! its kind, the fast tier's plan) is made once per task, as a
//! [`SidePlan`], and read by each of the task's blocks.

use glam::Vec3;

use super::block::{BLOCK, Block};
use super::directional::directional;
use super::fast_point::{self, FastPlan};
use super::positional::{AtPoint, positional};
use super::variant::{PointKind, Variant};
use super::{Kernel, SideProducts, Source, Viewer32};
use crate::LightMask;
use crate::fastmath::{Math, Power};

/// One light's colour products on one side.
pub(super) struct LightColors {
    pub ambient: Vec3,
    pub diffuse: Vec3,
    pub specular: Vec3,
    pub shininess: f32,
    /// The tier's plan for the power of the shininess.
    pub power: Power,
    /// The specular terms go to the block's secondary colour (see
    /// [`Kernel::separate_specular`]).
    pub separate: bool,
}

/// One side's lights as the blocks of a task read them, for the variant
/// `V` it was made for ([`SidePlan::new`]).
pub(super) struct SidePlan<'a> {
    /// `e_cm + a_cm·a_cs`, where every lane's colour starts.
    base: Vec3,
    /// The side's specular power is raised from `cos²` alone: its blocks
    /// run `V::FromCos2`, for which `lights` were planned.
    from_cos2: bool,
    /// The infinite viewer's direction (unused for a local one).
    eye: Vec3,
    lights: Vec<LightPlan<'a>>,
}

/// One light's plan on one side.
struct LightPlan<'a> {
    /// The light's place in the scene, for the visibility masks.
    index: usize,
    colors: LightColors,
    source: SourcePlan<'a>,
}

/// What a light's loops read of where it is.
enum SourcePlan<'a> {
    Directional {
        vp_pli: Vec3,
        spot: f32,
        half: Vec3,
    },
    AtPoint {
        at: AtPoint<'a>,
        kind: Kind,
        /// The fast tier's plan, where its path takes the light.
        fast: Option<FastPlan>,
    },
}

/// Which of a light at a point's factors the scene needs: the
/// [`PointLight`] its loops are monomorphised for.
#[derive(Clone, Copy)]
struct Kind {
    attenuated: bool,
    cone: bool,
    cone_from_cos2: bool,
}

/// `$body` with `$P` the [`PointKind`] of `$kind`.
macro_rules! with_kind {
    ($kind:expr, $P:ident => $body:expr) => {{
        macro_rules! as_kind {
            ($attenuated:literal, $cone:literal, $cos2:literal) => {{
                type $P = PointKind<$attenuated, $cone, $cos2>;
                $body
            }};
        }
        let Kind {
            attenuated,
            cone,
            cone_from_cos2,
        } = $kind;
        match (attenuated, cone, cone_from_cos2) {
            (false, false, _) => as_kind!(false, false, false),
            (true, false, _) => as_kind!(true, false, false),
            (false, true, false) => as_kind!(false, true, false),
            (true, true, false) => as_kind!(true, true, false),
            (false, true, true) => as_kind!(false, true, true),
            (true, true, true) => as_kind!(true, true, true),
        }
    }};
}

impl<'a> SidePlan<'a> {
    /// The plan of `side` for the blocks of a task of the variant `V`;
    /// `in_range`: the lights of [`Kernel::lights_in_range`] for the batch.
    #[inline(always)]
    pub fn new<V: Variant>(kernel: &'a Kernel, side: &SideProducts, in_range: LightMask) -> Self {
        let whole = matches!(V::M::power(&side.shininess_power), Power::Whole { .. });
        let from_cos2 = <V::M as Math>::WHOLE_FROM_COS2 && V::SPEC && !V::PHONG && !V::RAW && whole;
        let lights = if from_cos2 {
            plan_lights::<V::FromCos2>(kernel, side, in_range)
        } else {
            plan_lights::<V>(kernel, side, in_range)
        };
        Self {
            base: side.base,
            from_cos2,
            eye: infinite_eye(kernel),
            lights,
        }
    }
}

/// The infinite viewer's direction, or zero for a local viewer.
fn infinite_eye(kernel: &Kernel) -> Vec3 {
    match kernel.viewer {
        Viewer32::Infinite(dir) => dir,
        Viewer32::Local(_) => Vec3::ZERO,
    }
}

/// Every light's plan on `side` for the variant `V`.
fn plan_lights<'a, V: Variant>(
    kernel: &'a Kernel,
    side: &SideProducts,
    in_range: LightMask,
) -> Vec<LightPlan<'a>> {
    let separate = kernel.separate_specular();
    let eye = infinite_eye(kernel);
    let sources = kernel.sources.iter().zip(&side.products).enumerate();
    sources
        .map(|(index, (source, &[ambient, diffuse, specular]))| {
            let colors = LightColors {
                ambient,
                diffuse,
                specular,
                shininess: side.shininess,
                power: V::M::power(&side.shininess_power),
                separate,
            };
            let source = match source {
                &Source::Directional { vp_pli, spot, half } => {
                    SourcePlan::Directional { vp_pli, spot, half }
                }
                Source::Positional { p_pli, k, cone } => {
                    let at = AtPoint {
                        p_pli: *p_pli,
                        k: *k,
                        clamp: kernel.attenuation_clamp,
                        eye,
                        cone: cone.as_ref(),
                        in_range: in_range >> index & 1 == 1,
                    };
                    let kind = Kind {
                        attenuated: *k != [1.0, 0.0, 0.0],
                        cone: cone.is_some(),
                        cone_from_cos2: cone.is_some_and(|c| V::M::CONE_FROM_COS2 && c.from_cos2),
                    };
                    let fast = with_kind!(kind, P => fast_point::plan::<V, P>(&colors, &at));
                    SourcePlan::AtPoint { at, kind, fast }
                }
            };
            LightPlan {
                index,
                colors,
                source,
            }
        })
        .collect()
}

/// Every light of `plan` on one side of a block, by the variant the plan
/// was made for.
#[inline(always)]
pub(super) fn light_side<V: Variant>(block: &mut Block, plan: &SidePlan, separate: bool) {
    if plan.from_cos2 {
        light_block::<V::FromCos2>(block, plan, separate)
    } else {
        light_block::<V>(block, plan, separate)
    }
}

/// The block's colour starts at `e_cm + a_cm·a_cs`, and each light adds
/// its terms.
#[inline(always)]
fn light_block<V: Variant>(block: &mut Block, plan: &SidePlan, separate: bool) {
    for axis in 0..3 {
        block.primary[axis] = [plan.base[axis]; BLOCK];
        if separate {
            block.secondary[axis] = [0.0; BLOCK];
        }
    }
    for LightPlan {
        index,
        colors,
        source,
    } in &plan.lights
    {
        block.set_visible(*index);
        match source {
            &SourcePlan::Directional { vp_pli, spot, half } => {
                directional::<V>(block, colors, vp_pli, half, plan.eye, spot)
            }
            SourcePlan::AtPoint { at, kind, fast } => {
                with_kind!(*kind, P => positional::<V, P>(block, colors, at, fast.as_ref()))
            }
        }
    }
}
