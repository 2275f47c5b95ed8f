//! Section 2.14.1 for one side of a block: the light loop outside, the
//! vertex loops of each light's kind inside.

use glam::Vec3;

use super::block::{BLOCK, Block};
use super::directional::directional;
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

/// [`light_block`] with the specular cosine the side's power needs;
/// `in_range`: the lights of [`Kernel::lights_in_range`].
#[inline(always)]
pub(super) fn light_side<V: Variant>(
    kernel: &Kernel,
    block: &mut Block,
    side: &SideProducts,
    in_range: LightMask,
) {
    let whole = matches!(V::M::power(&side.shininess_power), Power::Whole { .. });
    if <V::M as Math>::WHOLE_FROM_COS2 && V::SPEC && !V::PHONG && !V::RAW && whole {
        light_block::<V::FromCos2>(kernel, block, side, in_range)
    } else {
        light_block::<V>(kernel, block, side, in_range)
    }
}

/// Every light of `kernel` on one side of a block: the block's colour starts
/// at `e_cm + a_cm·a_cs`, and each light adds its terms.
#[inline(always)]
fn light_block<V: Variant>(
    kernel: &Kernel,
    block: &mut Block,
    side: &SideProducts,
    in_range: LightMask,
) {
    let separate = kernel.separate_specular();
    for axis in 0..3 {
        block.primary[axis] = [side.base[axis]; BLOCK];
        if separate {
            block.secondary[axis] = [0.0; BLOCK];
        }
    }
    let infinite_eye = match kernel.viewer {
        Viewer32::Infinite(dir) => dir,
        Viewer32::Local(_) => Vec3::ZERO,
    };
    for (index, (source, &[ambient, diffuse, specular])) in
        kernel.sources.iter().zip(&side.products).enumerate()
    {
        block.set_visible(index);
        let light = LightColors {
            ambient,
            diffuse,
            specular,
            shininess: side.shininess,
            power: V::M::power(&side.shininess_power),
            separate,
        };
        match source {
            &Source::Directional { vp_pli, spot, half } => {
                directional::<V>(block, &light, vp_pli, half, infinite_eye, spot)
            }
            Source::Positional { p_pli, k, cone } => {
                // The cone by reference: a copy of its odd layout per block
                // costs a failed store forwarding.
                let at = AtPoint {
                    p_pli: *p_pli,
                    k: *k,
                    clamp: kernel.attenuation_clamp,
                    eye: infinite_eye,
                    cone: cone.as_ref(),
                    in_range: in_range >> index & 1 == 1,
                };
                let cone_from_cos2 = cone.is_some_and(|c| V::M::CONE_FROM_COS2 && c.from_cos2);
                let attenuated = *k != [1.0, 0.0, 0.0];
                macro_rules! run {
                    ($att:literal, $cone:literal, $cos2:literal) => {
                        positional::<V, PointKind<$att, $cone, $cos2>>(block, &light, &at)
                    };
                }
                match (attenuated, cone.is_some(), cone_from_cos2) {
                    (false, false, _) => run!(false, false, false),
                    (true, false, _) => run!(true, false, false),
                    (false, true, false) => run!(false, true, false),
                    (true, true, false) => run!(true, true, false),
                    (false, true, true) => run!(false, true, true),
                    (true, true, true) => run!(true, true, true),
                }
            }
        }
    }
}
