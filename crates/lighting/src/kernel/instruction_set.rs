//! The instruction sets a task function is built for, and which one runs.
//!
//! The kernel's task functions are compiled three times: for AVX-512F (with
//! AVX2 and FMA), for AVX2 with FMA, and for the x86-64 baseline (or any
//! other architecture). By default the widest the CPU has runs. Each build
//! keeps the tiers' bounds, and the kernel tests hold every build this CPU
//! runs to them, so a build never goes untested because the machine has a
//! wider one: [`InstructionSet::here`] lists them, and
//! [`Kernel::light_on`](super::Kernel::light_on) lights with a chosen one.
//!
//! An operator forces one for the whole process with [`ISA_VARIABLE`]
//! (`GLINT_KERNEL_ISA=avx512|avx2|baseline`): to compare builds, or to rule
//! one out on a CPU whose wide units slow its clock. [`InstructionSet::check_env`]
//! refuses a value the CPU cannot run, so a process fails at its start
//! rather than at its first request.

use std::fmt;
use std::str::FromStr;
use std::sync::OnceLock;

/// The environment variable that forces an instruction set for the process.
pub const ISA_VARIABLE: &str = "GLINT_KERNEL_ISA";

/// A build of the kernel's task functions, widest first.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum InstructionSet {
    /// AVX-512F with AVX2 and FMA: 16 lanes, the reciprocal and square
    /// root estimates of AVX-512.
    Avx512,
    /// AVX2 with FMA: 8 lanes.
    Avx2,
    /// What every CPU of the target architecture runs.
    Baseline,
}

impl InstructionSet {
    /// Every build, widest first.
    pub const ALL: [InstructionSet; 3] = [Self::Avx512, Self::Avx2, Self::Baseline];

    /// The name [`ISA_VARIABLE`] takes.
    pub fn name(self) -> &'static str {
        match self {
            Self::Avx512 => "avx512",
            Self::Avx2 => "avx2",
            Self::Baseline => "baseline",
        }
    }

    /// Whether this CPU runs this build.
    pub fn runs_here(self) -> bool {
        match self {
            Self::Baseline => true,
            #[cfg(target_arch = "x86_64")]
            Self::Avx2 => {
                std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma")
            }
            #[cfg(target_arch = "x86_64")]
            Self::Avx512 => Self::Avx2.runs_here() && std::is_x86_feature_detected!("avx512f"),
            #[cfg(not(target_arch = "x86_64"))]
            Self::Avx2 | Self::Avx512 => false,
        }
    }

    /// For a test of this build's own code: whether the CPU runs it, saying
    /// so on the test's output where it does not (the test then checks
    /// nothing).
    #[cfg(test)]
    pub(crate) fn runs_here_for_test(self) -> bool {
        let here = self.runs_here();
        if !here {
            eprintln!("no {self} build on this CPU: skipped");
        }
        here
    }

    /// The builds this CPU runs, widest first (never empty: the baseline).
    pub fn here() -> impl Iterator<Item = InstructionSet> {
        Self::ALL.into_iter().filter(|isa| isa.runs_here())
    }

    /// The build [`ISA_VARIABLE`] forces, if it is set: an error names a value
    /// that is no build, or one this CPU does not run.
    pub fn check_env() -> Result<Option<InstructionSet>, String> {
        let Some(value) = std::env::var_os(ISA_VARIABLE) else {
            return Ok(None);
        };
        let value = value.to_string_lossy();
        let isa: InstructionSet = value
            .parse()
            .map_err(|e| format!("{ISA_VARIABLE}={value}: {e}"))?;
        if !isa.runs_here() {
            return Err(format!(
                "{ISA_VARIABLE}={value}: this CPU does not run the {isa} build (it runs {})",
                Self::here().map(Self::name).collect::<Vec<_>>().join(", ")
            ));
        }
        Ok(Some(isa))
    }

    /// The build that runs when none is asked for: the one [`ISA_VARIABLE`]
    /// forces, else the widest this CPU runs. Read once per process; a
    /// value [`check_env`](Self::check_env) refuses counts as unset.
    pub fn chosen() -> InstructionSet {
        static CHOSEN: OnceLock<InstructionSet> = OnceLock::new();
        *CHOSEN.get_or_init(|| {
            Self::check_env()
                .ok()
                .flatten()
                .unwrap_or_else(|| Self::here().next().unwrap_or(Self::Baseline))
        })
    }
}

impl fmt::Display for InstructionSet {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for InstructionSet {
    type Err = String;

    fn from_str(name: &str) -> Result<Self, String> {
        Self::ALL
            .into_iter()
            .find(|isa| isa.name() == name)
            .ok_or_else(|| {
                format!(
                    "no build of the kernel is named {name:?} (the builds: {})",
                    Self::ALL.map(Self::name).join(", ")
                )
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_read_back_and_the_baseline_always_runs() {
        for isa in InstructionSet::ALL {
            assert_eq!(isa.name().parse::<InstructionSet>(), Ok(isa));
        }
        assert!("sse9".parse::<InstructionSet>().is_err());
        assert!(InstructionSet::here().any(|isa| isa == InstructionSet::Baseline));
        assert!(InstructionSet::chosen().runs_here());
    }

    #[test]
    fn a_wider_build_runs_only_where_the_narrower_does() {
        let runs: Vec<bool> = InstructionSet::ALL.map(InstructionSet::runs_here).to_vec();
        // Widest first: once one runs, every narrower one runs.
        assert!(runs.windows(2).all(|w| !w[0] || w[1]), "{runs:?}");
    }
}
