// The only header that includes xsimd. Kernels use `fbatch` (the widest float batch of the target: 16 lanes with
// AVX-512) and the few helpers below, so the rest of the engine never depends on the SIMD library's API directly.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <xsimd/xsimd.hpp>

#if defined(__AVX512F__)
#include <immintrin.h>
#endif

namespace drape::simd {

using fbatch = xsimd::batch<float>;
using ubatch = xsimd::batch<std::uint32_t>;
using fmask = xsimd::batch_bool<float>;

/// Number of float lanes: every hot array is padded to a multiple of this.
inline constexpr std::size_t width = fbatch::size;

inline fbatch load(const float* p) noexcept { return fbatch::load_aligned(p); }
inline fbatch loadu(const float* p) noexcept { return fbatch::load_unaligned(p); }
inline void store(float* p, fbatch v) noexcept { v.store_aligned(p); }
inline ubatch load(const std::uint32_t* p) noexcept { return ubatch::load_aligned(p); }
inline fbatch splat(float v) noexcept { return fbatch(v); }

/// a * b + c with a single rounding (explicit: the build disables implicit contraction). xsimd 8.1 has no AVX-512
/// fma (its generic fallback is a * b + c, two instructions and two roundings), so AVX-512 uses the intrinsic; AVX2
/// with FMA3 goes through xsimd's fma3 kernels; a target without FMA hardware rounds twice.
inline fbatch fma(fbatch a, fbatch b, fbatch c) noexcept {
#if defined(__AVX512F__)
    return fbatch(_mm512_fmadd_ps(a, b, c));
#else
    return xsimd::fma(a, b, c);
#endif
}
/// The scalar lane of fma: std::fma, one rounding (a scalar twin written once for float and fbatch calls it).
inline float fma(float a, float b, float c) noexcept { return std::fma(a, b, c); }
/// c - a * b with a single rounding (same notes as fma).
inline fbatch fnma(fbatch a, fbatch b, fbatch c) noexcept {
#if defined(__AVX512F__)
    return fbatch(_mm512_fnmadd_ps(a, b, c));
#else
    return xsimd::fnma(a, b, c);
#endif
}
inline fbatch select(fmask m, fbatch a, fbatch b) noexcept { return xsimd::select(m, a, b); }

using ibatch = xsimd::batch<std::int32_t>;
/// Loads width 32-bit indices (aligned) for gather().
inline ibatch load_indices(const std::uint32_t* p) noexcept {
    return ibatch::load_aligned(reinterpret_cast<const std::int32_t*>(p));
}
/// base[idx[k]] per lane. AVX-512: the hardware gather (xsimd 8.1's gather is a lane-by-lane loop, an out-of-line
/// call: measured 31 % of the implicit sweeps).
inline fbatch gather(const float* base, ibatch idx) noexcept {
#if defined(__AVX512F__)
    // The masked form with a zero source: the plain one reads an undefined source register (g++ 12 warns).
    return fbatch(_mm512_mask_i32gather_ps(_mm512_setzero_ps(), __mmask16(0xFFFF), idx, base, 4));
#else
    return fbatch::gather(base, idx);
#endif
}

/// 1/sqrt(x) to ~23 bits. AVX-512: rsqrt14 estimate plus one Newton-Raphson step (xsimd 8.1's own AVX-512 rsqrt
/// calls an intrinsic g++ 12 lacks). Elsewhere: 1/sqrt. Relative error below 1e-7 after the Newton step; the
/// scalar reference in tests/ uses exact 1/sqrt in double and compares with a tolerance.
inline fbatch rsqrt(fbatch x) noexcept {
#if defined(__AVX512F__)
    static_assert(fbatch::size == 16, "AVX-512 path expects 16 float lanes");
    const fbatch y = fbatch(_mm512_rsqrt14_ps(x));
    // y * (1.5 - 0.5 * x * y * y)
    const fbatch hx = fbatch(0.5f) * x;
    return y * fnma(hx * y, y, fbatch(1.5f));
#else
    return fbatch(1.0f) / xsimd::sqrt(x);
#endif
}

/// rsqrt for one float, bit for bit one lane of rsqrt above (the same estimate, the same Newton step): the scalar
/// reference of a kernel that uses rsqrt gives its bits.
inline float rsqrt(float x) noexcept {
#if defined(__AVX512F__)
    const float y = _mm_cvtss_f32(_mm_rsqrt14_ss(_mm_setzero_ps(), _mm_set_ss(x)));
    const float hx = 0.5f * x;
    return y * std::fma(-(hx * y), y, 1.5f);
#else
    return 1.0f / std::sqrt(x);
#endif
}

/// Lanes whose 32-bit mask word has any bit of `bits` set.
inline fmask test_bits(ubatch words, std::uint32_t bits) noexcept {
#if defined(__AVX512F__)
    return fmask(_mm512_test_epi32_mask(words, _mm512_set1_epi32(static_cast<int>(bits))));
#else
    // xsimd 8.1 has no batch_bool_cast: the hit bits (below 2^24) convert exactly to float.
    const ubatch hit = words & ubatch(bits);
    return xsimd::to_float(xsimd::bitwise_cast<xsimd::batch<std::int32_t>>(hit)) != fbatch(0.0f);
#endif
}

/// True when every lane of v is finite (not inf, not NaN).
inline bool all_finite(fbatch v) noexcept { return xsimd::all((v - v) == fbatch(0.0f)); }
inline fmask finite_lanes(fbatch v) noexcept { return (v - v) == fbatch(0.0f); }

} // namespace drape::simd
