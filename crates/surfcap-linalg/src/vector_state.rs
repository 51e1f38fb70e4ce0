//! Clearing the upper halves of the vector registers (`vzeroupper`) when the CPU has AVX.
//!
//! faer's AVX-512 kernels (its GEMM) leave the upper register state dirty. Scalar SSE code that
//! calls libm (`acos`, `ln`, `exp`, `asin`, which are VEX-encoded on FMA machines) afterwards on
//! the same thread then ran 5-6 times slower: measured on this project's 2-core Xeon, where the
//! penalty showed at the libm call and return. Clearing the state first restored the speed. Call
//! it before such scalar loops on a thread that may have run faer's kernels.

/// Clears the upper halves of the vector registers (`vzeroupper`) when the CPU has AVX; does
/// nothing elsewhere.
#[inline]
pub fn clear_upper_vector_state() {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx") {
            // SAFETY: `vzeroupper` only requires AVX, checked at run time just above.
            unsafe { zeroupper() }
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn zeroupper() {
    std::arch::x86_64::_mm256_zeroupper();
}

#[cfg(test)]
mod tests {
    #[test]
    fn clearing_the_state_leaves_values_alone() {
        let x = std::hint::black_box(0.5f64);
        super::clear_upper_vector_state();
        assert_eq!(x.acos(), 0.5f64.acos());
    }
}
