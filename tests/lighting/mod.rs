//! Tests of the lighting core (`glint_lighting`): the OpenGL 2.1 lighting
//! equation of section 2.14.1 of the compatibility specification,
//!
//! ```text
//! c = e_cm + a_cm·a_cs
//!   + Σ_i att_i · spot_i · [a_cm·a_cli + (n⊙VP_pli) d_cm·d_cli + f_i (n⊙ĥ_i)^s_rm s_cm·s_cli]
//! ```
//!
//! - [`golden`]: one hand-computed case per term of the equation and per
//!   option of the light model, and GL's default state.
//! - [`edge_cases`]: the decisions listed in the module docs of
//!   `glint_lighting` (0^0 = 1, the spot cone's edges, zero vectors, ...).
//! - [`breakdown`]: the per-term explanation (`Breakdown`) and its batch
//!   statistics (`Summary`).
//! - [`kernel`]: the f32 `Kernel` (both tiers, with and without visibility
//!   masks) against the f64 reference, within each tier's documented bound.
//! - [`properties`]: invariants over random scenes (proptest).
//! - [`instruction_sets`]: each build of the kernel the CPU runs, forced for
//!   the binary by `GLINT_KERNEL_ISA`, against the reference tier.
//!
//! Every expected number is written as arithmetic from the specification,
//! with the derivation in a comment; none is copied from glint's output.

// `support` first: `#[macro_use]` makes `assert_close!` visible to the
// modules declared after it.
#[macro_use]
pub(crate) mod support;

mod breakdown;
mod edge_cases;
mod golden;
mod instruction_sets;
mod kernel;
mod properties;
