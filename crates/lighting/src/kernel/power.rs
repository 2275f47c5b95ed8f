//! Raising a block's stored cosines to a power: `(n⊙ĥ)^s` and the spot's
//! `(P_pli V ⊙ ŝ)^e`, by the tier's plan ([`Power`]): one for `s = 0`
//! (0^0 = 1), multiplication for whole powers of `cos²`, `pow` otherwise.

use super::block::{BLOCK, Block};
use crate::fastmath::{Cosine, Math, Power, whole_base};

/// Stores a cosine of lane `i` for [`power_block`].
#[inline(always)]
pub(super) fn store_cosine(b: &mut Block, i: usize, c: Cosine) {
    b.sin2[i] = c.sin2;
    b.cos2[i] = if c.positive { c.cos2 } else { -1.0 };
}

/// Stores lane `i`'s `cos²` alone, for [`power_block`] `from_cos2`.
#[inline(always)]
pub(super) fn store_cos2(b: &mut Block, i: usize, positive: bool, cos2: f32) {
    b.cos2[i] = if positive { cos2 } else { -1.0 };
}

/// `power` of every lane's stored cosine into `b.power`: see [`Power`].
/// `from_cos2`: the cosines are in `cos2` alone (`sin2` is not read); a
/// constant of the inlined caller's variant.
#[inline(always)]
pub(super) fn power_block<M: Math>(power: Power, b: &mut Block, from_cos2: bool) {
    match power {
        Power::One => b.power = [1.0; BLOCK],
        Power::General(s) => {
            for i in 0..BLOCK {
                let c = stored_cosine(b, i, from_cos2);
                let c = Cosine {
                    cos2: c.cos2.max(0.0),
                    ..c
                };
                b.power[i] = M::pow_cosine(c, s);
            }
        }
        // The usual exponents (shininess 2 to 128) in one pass.
        Power::Whole { n, cutoff } if n.is_power_of_two() && n <= 64 => match n.trailing_zeros() {
            0 => squared_block::<0>(b, cutoff, from_cos2),
            1 => squared_block::<1>(b, cutoff, from_cos2),
            2 => squared_block::<2>(b, cutoff, from_cos2),
            3 => squared_block::<3>(b, cutoff, from_cos2),
            4 => squared_block::<4>(b, cutoff, from_cos2),
            5 => squared_block::<5>(b, cutoff, from_cos2),
            _ => squared_block::<6>(b, cutoff, from_cos2),
        },
        Power::Whole { n, cutoff } => binary_power_block(b, n, cutoff, from_cos2),
    }
}

/// [`Power::Whole`] for any `n`: binary powering, one pass over the block
/// per step.
#[inline(always)]
fn binary_power_block(b: &mut Block, n: u32, cutoff: f32, from_cos2: bool) {
    let mut base = [0.0; BLOCK];
    for i in 0..BLOCK {
        base[i] = whole_base(stored_cosine(b, i, from_cos2), cutoff);
    }
    let mut n = n;
    let mut first = true;
    loop {
        if n & 1 == 1 {
            if first {
                b.power = base;
                first = false;
            } else {
                for i in 0..BLOCK {
                    b.power[i] *= base[i];
                }
            }
        }
        n >>= 1;
        if n == 0 {
            break;
        }
        for x in base.iter_mut() {
            *x *= *x;
        }
    }
}

/// The stored cosine of lane `i`; `from_cos2`: `sin²` = 1, which sends
/// [`whole_base`] to `cos²`.
#[inline(always)]
fn stored_cosine(b: &Block, i: usize, from_cos2: bool) -> Cosine {
    Cosine {
        positive: b.cos2[i] >= 0.0,
        sin2: if from_cos2 { 1.0 } else { b.sin2[i] },
        cos2: b.cos2[i],
    }
}

/// [`Power::Whole`] for `n = 2^K`: `K` squarings of each lane's base, in
/// registers, where binary powering for any `n` takes a pass over the block
/// per step.
#[inline(always)]
fn squared_block<const K: u32>(b: &mut Block, cutoff: f32, from_cos2: bool) {
    for i in 0..BLOCK {
        let mut x = whole_base(stored_cosine(b, i, from_cos2), cutoff);
        for _ in 0..K {
            x *= x;
        }
        b.power[i] = x;
    }
}
