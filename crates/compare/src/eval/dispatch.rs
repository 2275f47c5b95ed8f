//! Running a piece of work built for the widest instruction set the CPU
//! has, as the kernels' tasks are: AVX-512 or AVX2 with FMA. Without FMA,
//! each `mul_add` of the tiers' polynomials is a library call.

/// Work whose `run` is inlined into a build per instruction set.
pub(crate) trait Work {
    type Out;
    fn run(self) -> Self::Out;
}

/// Runs `work` in the widest build the CPU runs.
pub(crate) fn run<W: Work>(work: W) -> W::Out {
    #[cfg(target_arch = "x86_64")]
    {
        if std::is_x86_feature_detected!("avx512f")
            && std::is_x86_feature_detected!("avx2")
            && std::is_x86_feature_detected!("fma")
        {
            // SAFETY: the CPU has AVX-512F, AVX2 and FMA, checked just above.
            return unsafe { run_avx512(work) };
        }
        if std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma") {
            // SAFETY: the CPU has AVX2 and FMA, checked just above.
            return unsafe { run_avx2(work) };
        }
    }
    work.run()
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx2,fma")]
fn run_avx512<W: Work>(work: W) -> W::Out {
    work.run()
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn run_avx2<W: Work>(work: W) -> W::Out {
    work.run()
}
