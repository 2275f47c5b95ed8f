//! The compile-time shape of a vertex loop: one type parameter that carries
//! the tier's arithmetic, the instruction set's reciprocals and the scene's
//! [`StateKey`](super::StateKey), so that each loop is monomorphised for
//! its scene without a list of flags in every signature.

use std::marker::PhantomData;

use super::isa::Isa;
use crate::fastmath::Math;

/// A monomorphised vertex loop's tier, instruction set and scene features.
pub(super) trait Variant {
    type M: Math;
    type I: Isa;
    /// A local viewer: `VP_e` per vertex.
    const LOCAL: bool;
    /// Some light has a specular product.
    const SPEC: bool;
    /// Phong's `(r⊙VP_e)^s` in place of `(n⊙ĥ)^s`.
    const PHONG: bool;
    /// Normals used as given: the specular base is not a cosine.
    const RAW: bool;
    /// The specular power is whole and taken from `cos²` alone (see
    /// [`Math::WHOLE_FROM_COS2`]).
    const COS2: bool;
    /// The same loop with [`Variant::COS2`] set.
    type FromCos2: Variant<M = Self::M, I = Self::I>;
}

/// The [`Variant`] of these parameters.
pub(super) struct Loop<
    M,
    I,
    const LOCAL: bool,
    const SPEC: bool,
    const PHONG: bool,
    const RAW: bool,
    const COS2: bool,
>(PhantomData<(M, I)>);

impl<
    M: Math,
    I: Isa,
    const LOCAL: bool,
    const SPEC: bool,
    const PHONG: bool,
    const RAW: bool,
    const COS2: bool,
> Variant for Loop<M, I, LOCAL, SPEC, PHONG, RAW, COS2>
{
    type M = M;
    type I = I;
    const LOCAL: bool = LOCAL;
    const SPEC: bool = SPEC;
    const PHONG: bool = PHONG;
    const RAW: bool = RAW;
    const COS2: bool = COS2;
    type FromCos2 = Loop<M, I, LOCAL, SPEC, PHONG, RAW, true>;
}

/// What a light at a point needs per vertex beyond its direction.
pub(super) trait PointLight {
    /// The attenuation coefficients are not (1, 0, 0).
    const ATTENUATED: bool;
    /// A cone (a cutoff other than 180).
    const CONE: bool;
    /// The cone is tested on `cos²` alone (see [`Math::CONE_FROM_COS2`]).
    const CONE_FROM_COS2: bool;
}

/// The [`PointLight`] of these parameters.
pub(super) struct PointKind<const ATTENUATED: bool, const CONE: bool, const CONE_FROM_COS2: bool>;

impl<const ATTENUATED: bool, const CONE: bool, const CONE_FROM_COS2: bool> PointLight
    for PointKind<ATTENUATED, CONE, CONE_FROM_COS2>
{
    const ATTENUATED: bool = ATTENUATED;
    const CONE: bool = CONE;
    const CONE_FROM_COS2: bool = CONE_FROM_COS2;
}
