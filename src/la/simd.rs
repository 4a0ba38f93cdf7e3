//! Run-time choice of the instruction set for a few hot loops. The build targets the baseline
//! of its architecture (a binary runs on any x86-64 processor); the loops that gain from wider
//! vectors have a second copy compiled for AVX2, taken when the processor has it. The two do
//! the same floating-point operations in the same order (Rust never fuses `a * b + c`), so a
//! run's results are bit for bit the same on either path (`STICKSLIP_SIMD=baseline` forces the
//! baseline, for that comparison).

/// Whether the processor has AVX2 and the baseline is not forced (checked once).
#[cfg(target_arch = "x86_64")]
pub fn avx2() -> bool {
    static AVX2: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *AVX2.get_or_init(|| {
        std::env::var("STICKSLIP_SIMD").as_deref() != Ok("baseline")
            && std::is_x86_feature_detected!("avx2")
    })
}

/// Whether the processor has AVX2 (never, off x86-64).
#[cfg(not(target_arch = "x86_64"))]
pub fn avx2() -> bool {
    false
}
