// One sweep of Provot strain limiting over a range of springs (core/src/strain_limit.cpp runs it group by group), and
// the bookkeeping that lets later sweeps skip the groups in which nothing moved: each correction stamps the groups of
// its two particles with the sweep's running sequence number, and a group whose stamp is older than its own last
// visit holds the same positions it was checked at, so none of its springs can be over the limit.
#pragma once

#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>

namespace drape::strain_limit {

/// Flags of Simulation::limit_inner_: end a (b) is fewer springs away from the authored pins than the other end; the
/// spring is a shear spring; a seam spring; no fixed particle is connected to it (a cloth without pins or grab).
inline constexpr std::uint8_t a_inner = 1, b_inner = 2, shear = 4, seam = 8, unpinned = 16;

struct Args {
    float* __restrict x;
    float* __restrict y;
    float* __restrict z;
    float* __restrict u;
    float* __restrict v;
    float* __restrict w;
    const float* __restrict inv_mass;
    const std::uint32_t* __restrict a;
    const std::uint32_t* __restrict b;
    const float* __restrict rest;
    /// Per spring limit_inner_'s flags for the frame form (one-sided: only the far end moves; no shear spring;
    /// velocities follow two-sided corrections only), or null for the explicit solver's form (also while a grab is
    /// held).
    const std::uint8_t* __restrict inner;
    float stretch;   ///< 1 + ratio
    /// 1 + strain_limit_tolerance ratio: a spring longer than this before its correction keeps the sweeps going
    float tolerated;
    /// Frame form: 1 - ratio, the shortest a structural spring may be (0 in the explicit form: no bound). Its
    /// one-sided corrections pull a particle next to a clip along each stretched spring towards the clip, which
    /// squeezed the springs between it and the clip's other particles by up to 22 % (N = 200) and 36 % (N = 316)
    /// at 0.6 - 1.4 s of the wool hang with the limit at 0.095 (docs/implicit.md, "Compression next to the
    /// clips").
    float squeeze;
    float squeeze_tolerated; ///< 1 - strain_limit_tolerance ratio: shorter keeps the sweeps going
    /// Change of u, v, w per unit displacement: Euler (velocity) 1 / (K dt), Verlet (displacement per step) 1 / K;
    /// frame form (implicit, Euler's velocities) 1 / (K h), for the corrections that move both ends only.
    float vel_scale;
    /// Per particle (CSR), the colour groups holding one of its springs; per group the sequence number of the last
    /// correction that moved one of its particles.
    const std::uint32_t* __restrict particle_group_offsets;
    const std::uint32_t* __restrict particle_groups;
    std::uint64_t* group_moved;
    /// Frame form: the end nearer the fixed particles stays (the first strain_limit_one_sided_passes sweeps of a
    /// step), else both ends move by inverse mass.
    bool one_sided = true;
    /// A mirror-exact cloth: per spring pair_first / pair_second for the two springs that meet at a particle on the
    /// mirror line (adjacent slots of a colour group, solved together), else 0; null on other cloths.
    const std::uint8_t* __restrict pair = nullptr;
};

/// Args::pair's values.
inline constexpr std::uint8_t pair_first = 1, pair_second = 2;

/// A spring's correction, found before it is applied (so two springs can be found from the same positions).
struct Correction {
    std::uint32_t ia, ib;
    float dx, dy, dz; ///< x_b - x_a
    float ea, eb;     ///< x_a += ea d, x_b -= eb d
    bool velocities;  ///< the velocities follow
};

/// Spring k: d = x_b - x_a, l = |d|; over l_max = stretch rest its ends move toward each other by the excess (frame
/// form: under squeeze rest, a structural spring's ends move apart by the shortfall), shared by inverse mass (x_a += w_a e d, x_b -= w_b e d, e = (l - l_max) / (l (w_a + w_b))). Returns `over` if it was
/// longer than the tolerated stretch, plus `moved` if its ends were moved. Frame: the implicit solver's form
/// (c.inner set), else the explicit solver's.
inline constexpr unsigned over = 1, moved = 2;
/// Finds spring k's correction (into `out` when the result has `moved`) without applying it.
template <bool Frame> inline unsigned find_correction(const Args& c, std::size_t k, Correction& out) noexcept {
    if (Frame && (c.inner[k] & shear)) return 0; // the implicit solver limits no shear spring
    const std::uint32_t ia = c.a[k], ib = c.b[k];
    const float dx = c.x[ib] - c.x[ia], dy = c.y[ib] - c.y[ia], dz = c.z[ib] - c.z[ia];
    const float l2 = dx * dx + dy * dy + dz * dz;
    float l_max = c.stretch * c.rest[k];
    unsigned is_over;
    if (l2 > l_max * l_max) {
        const float l_tol = c.tolerated * c.rest[k];
        is_over = l2 > l_tol * l_tol ? over : 0;
    } else {
        // Frame form, a structural spring shorter than squeeze x rest: its ends move apart by the shortfall (the
        // same formula with l_max = the shortest length: e < 0). A spring of zero length has no direction.
        if (!Frame || (c.inner[k] & seam)) return 0;
        const float l_min = c.squeeze * c.rest[k];
        if (!(l2 < l_min * l_min) || l2 == 0.0f) return 0;
        const float l_tol = c.squeeze_tolerated * c.rest[k];
        is_over = l2 < l_tol * l_tol ? over : 0;
        l_max = l_min;
    }
    float wa = c.inv_mass[ia], wb = c.inv_mass[ib];
    if (Frame && c.one_sided) { // the end nearer the fixed particles stays (unless the far end cannot move)
        if ((c.inner[k] & a_inner) && wb != 0.0f) wa = 0.0f;
        if ((c.inner[k] & b_inner) && wa != 0.0f) wb = 0.0f;
    }
    const float wsum = wa + wb;
    if (wsum == 0.0f) return is_over;
    const float l = std::sqrt(l2);
    const float e = (l - l_max) / (l * wsum);
    // Frame form: positions only, but in a part of the cloth that no fixed particle is connected to (a garment
    // without pins: every correction there moves both ends by inverse mass, the mass-orthogonal projection), where
    // the velocities follow as in the explicit form (v += dx / h): momentum is kept and kinetic energy only removed.
    // With positions only there as well, the tank top blew up at 1.07 s with the limit at 0.1 (structural strain
    // 1.54; 0.27 with no limit at all): each step's velocities kept the motion the limit had taken back, and the next
    // step's inertial prediction carried the shoulder straps out again. Where a fixed particle is connected, one-sided
    // corrections (an end held though it could move) with the velocities following would drag the far end along
    // without slowing the near one (the whip of issue 10), and two-sided ones beside the positions-only ones next to
    // a pin gathered every sweep's pull into a particle's velocity (a 48 x 48 hang dragged out of reach: 3,736 J in
    // 2 steps). docs/implicit.md, "Velocities after a correction of an unpinned cloth".
    out = Correction{ia, ib, dx, dy, dz, wa * e, wb * e, !Frame || (c.inner[k] & unpinned) != 0};
    return is_over | moved;
}

/// Applies a correction: the positions, then (if they follow) the velocities.
inline void apply_correction(const Args& c, const Correction& r) noexcept {
    // Moves a's entry of (px, py, pz) by sa d and b's by -sb d.
    const auto toward = [&](float* px, float* py, float* pz, float sa, float sb) {
        px[r.ia] += sa * r.dx;
        py[r.ia] += sa * r.dy;
        pz[r.ia] += sa * r.dz;
        px[r.ib] -= sb * r.dx;
        py[r.ib] -= sb * r.dy;
        pz[r.ib] -= sb * r.dz;
    };
    toward(c.x, c.y, c.z, r.ea, r.eb);
    if (r.velocities) toward(c.u, c.v, c.w, r.ea * c.vel_scale, r.eb * c.vel_scale);
}

template <bool Frame> inline unsigned limit_spring(const Args& c, std::size_t k) noexcept {
    Correction r;
    const unsigned result = find_correction<Frame>(c, k, r);
    if (result & moved) apply_correction(c, r);
    return result;
}

/// Springs k and k + 1, which meet at a particle on the mirror line (Args::pair): both corrections found from the
/// same positions, then applied, so the two halves of a mirror-symmetric state are treated alike (one after the
/// other, the second would see the first's move of the shared particle).
template <bool Frame> inline unsigned limit_pair(const Args& c, std::size_t k) noexcept {
    Correction r0, r1;
    const unsigned f0 = find_correction<Frame>(c, k, r0), f1 = find_correction<Frame>(c, k + 1, r1);
    if (f0 & moved) apply_correction(c, r0);
    if (f1 & moved) apply_correction(c, r1);
    return f0 | f1;
}

/// Stamps every group holding a spring of particle i with seq. Chunks of one group run in parallel and all store
/// the same seq, hence the relaxed atomic stores.
inline void mark_moved(const Args& c, std::uint32_t i, std::uint64_t seq) noexcept {
    for (std::uint32_t k = c.particle_group_offsets[i]; k < c.particle_group_offsets[i + 1]; ++k)
        std::atomic_ref<std::uint64_t>(c.group_moved[c.particle_groups[k]]).store(seq, std::memory_order_relaxed);
}

/// Springs begin..end-1 in order, the sweep at sequence number seq. Returns whether one was longer than the
/// tolerated stretch before its correction.
template <bool Frame> inline bool sweep(const Args& c, std::size_t begin, std::size_t end, std::uint64_t seq) noexcept {
    unsigned any = 0;
    for (std::size_t k = begin; k < end; ++k) {
        if (c.pair && c.pair[k] == pair_second) continue; // solved with the slot before (in this range or the last)
        if (c.pair && c.pair[k] == pair_first) {
            const unsigned r = limit_pair<Frame>(c, k);
            if (r & moved)
                for (std::size_t s = k; s <= k + 1; ++s) mark_moved(c, c.a[s], seq), mark_moved(c, c.b[s], seq);
            any |= r;
            continue;
        }
        const unsigned r = limit_spring<Frame>(c, k);
        if (r & moved) {
            mark_moved(c, c.a[k], seq);
            mark_moved(c, c.b[k], seq);
        }
        any |= r;
    }
    return (any & over) != 0;
}

inline bool sweep(const Args& c, std::size_t begin, std::size_t end, std::uint64_t seq) noexcept {
    return c.inner ? sweep<true>(c, begin, end, seq) : sweep<false>(c, begin, end, seq);
}

} // namespace drape::strain_limit
