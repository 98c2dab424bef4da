// Stage 5: Provot strain limiting ("inverse dynamics", seed 001 section 2; X. Provot, Deformation constraints in a
// mass-spring model to describe rigid cloth behavior, 1995).
//
// After integration, a spring of rest length l0 longer than l_max = (1 + ratio) l0 has its ends moved toward each
// other by the excess, shared by inverse mass (a pinned end does not move):
//   d = x_b - x_a, l = |d|, e = (l - l_max) / (l (w_a + w_b)),  x_a += w_a e d,  x_b -= w_b e d.
// Velocities follow the positions, so the integrator's state stays consistent and the correction cannot inject
// energy: with K = 1 (Provot's after-each-step) symplectic Euler gets v = (x_corrected - x_old) / dt, i.e.
// v += dx / dt, and Verlet's displacement d = x - x_prev (its velocity times dt) gets d += dx. When limiting runs
// after every K-th substep the excess built up over K dt, so Euler gets v += dx / (K dt) and Verlet d += dx / K.
// Why the weights must be the true inverse masses: the correction is then the mass-orthogonal projection onto the
// constraint, whose impulse conserves momentum and only removes kinetic energy (a perfectly inelastic constraint). An
// earlier version moved only the end farther from the pins (as if the inner end were infinitely heavy); that drags
// the outer particle along with the inner one's velocity without slowing the inner one - a whip that pumped a
// 0.1 kg cloth to 3,493 J (issue 10: --size 32 --stiffness 100 --strain-limit 0.01). It is gone.
// Springs are processed colour group by colour group (no two springs of a group share a particle: plain writes, in
// parallel), groups in a fixed order, `passes` times; overflow groups serially. Results do not depend on the thread
// count.
//
// Order: plain Gauss-Seidel over greedy colours converges slowly when the stretch is global (a cloth hanging from
// pins carries its whole weight outward from them). So the springs are levelled by breadth-first distance from the
// authored pins (level of a spring = the larger level of its ends), coloured level by level and processed from the
// pins outward: each pass carries a correction from the pins to the free edge. A cloth without pins has a single
// level. User pins and grabs (inverse mass 0) keep their ends fixed.
// With colliders, Simulation::step interleaves: sweep, collide, sweep, collide, ... (collide last), so a particle a
// collider pushed out is limited again and no particle ends a substep inside a collider.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <span>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "drape/simulation.hpp"

namespace drape {

namespace {

/// Springs per parallel chunk of a colour group (fixed: the partition never depends on the thread count).
constexpr std::size_t limit_chunk = 4096;
/// Flags of Simulation::limit_inner_: end a (b) is fewer springs away from the authored pins than the other end; the
/// spring is a shear spring.
constexpr std::uint8_t limit_a_inner = 1, limit_b_inner = 2, limit_shear = 4;

struct LimitArgs {
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
    const std::uint8_t* __restrict inner; ///< null (explicit solver), or per spring limit_inner_'s flags (implicit)
    bool one_sided;                        ///< with `inner`: move only the far end (not while a grab is held)
    float stretch;     ///< 1 + ratio
    float tolerated;   ///< 1 + 1.05 ratio: a spring longer than this before its correction keeps the sweeps going
    /// Change of u, v, w per unit displacement: Euler (velocity) 1 / (K dt), Verlet (displacement per step) 1 / K.
    float vel_scale;
};

/// Returns whether a spring of [begin, end) was longer than the tolerated stretch before its correction.
bool limit_range(const LimitArgs& c, std::size_t begin, std::size_t end) noexcept {
    bool over = false;
    for (std::size_t k = begin; k < end; ++k) {
        if (c.inner && (c.inner[k] & limit_shear)) continue; // the implicit solver limits no shear spring
        const std::uint32_t ia = c.a[k], ib = c.b[k];
        const float dx = c.x[ib] - c.x[ia], dy = c.y[ib] - c.y[ia], dz = c.z[ib] - c.z[ia];
        const float l2 = dx * dx + dy * dy + dz * dz;
        const float l_max = c.stretch * c.rest[k];
        if (!(l2 > l_max * l_max)) continue;
        const float l_tol = c.tolerated * c.rest[k];
        over = over || l2 > l_tol * l_tol;
        float wa = c.inv_mass[ia], wb = c.inv_mass[ib];
        if (c.one_sided) { // the end nearer the fixed particles stays (unless the far end cannot move)
            if ((c.inner[k] & limit_a_inner) && wb != 0.0f) wa = 0.0f;
            if ((c.inner[k] & limit_b_inner) && wa != 0.0f) wb = 0.0f;
        }
        const float wsum = wa + wb;
        if (wsum == 0.0f) continue;
        const float l = std::sqrt(l2);
        const float e = (l - l_max) / (l * wsum);
        const float ea = wa * e, eb = wb * e;
        c.x[ia] += ea * dx;
        c.y[ia] += ea * dy;
        c.z[ia] += ea * dz;
        c.x[ib] -= eb * dx;
        c.y[ib] -= eb * dy;
        c.z[ib] -= eb * dz;
        const float va = ea * c.vel_scale, vb = eb * c.vel_scale;
        c.u[ia] += va * dx;
        c.v[ia] += va * dy;
        c.w[ia] += va * dz;
        c.u[ib] -= vb * dx;
        c.v[ib] -= vb * dy;
        c.w[ib] -= vb * dz;
    }
    return over;
}

} // namespace

void Simulation::cook_strain_limit() {
    if (!limit_a_.empty() || cloth_.edges.empty()) return;
    const std::size_t n = cloth_.particle_count;
    std::vector<std::uint32_t> limited;
    for (std::uint32_t k = 0; k < cloth_.edges.size(); ++k)
        if (cloth_.edges[k].kind != SpringKind::bend) limited.push_back(k);

    // Adjacency over the limited springs (kept: update_limit_levels walks it again when pins or grabs change).
    std::vector<std::uint32_t>& adj_offsets = limit_adj_offsets_;
    std::vector<std::uint32_t>& adj = limit_adj_;
    adj_offsets.assign(n + 1, 0);
    for (std::uint32_t k : limited) {
        ++adj_offsets[cloth_.edges[k].a + 1];
        ++adj_offsets[cloth_.edges[k].b + 1];
    }
    for (std::size_t i = 0; i < n; ++i) adj_offsets[i + 1] += adj_offsets[i];
    adj.resize(adj_offsets[n]);
    {
        std::vector<std::uint32_t> fill(adj_offsets.begin(), adj_offsets.end() - 1);
        for (std::uint32_t k : limited) {
            adj[fill[cloth_.edges[k].a]++] = cloth_.edges[k].b;
            adj[fill[cloth_.edges[k].b]++] = cloth_.edges[k].a;
        }
    }
    limit_level_.resize(n);
    limit_queue_.resize(n);
    // Breadth-first levels from the authored pins: the order of the passes.
    limit_levels(inv_mass_authored_.data());
    const std::vector<std::uint32_t>& level = limit_level_; // update_limit_levels below refills it, after the sort
    // Springs by level (the larger level of the two ends; unreached parts last), stable within a level.
    auto spring_level = [&](std::uint32_t k) {
        return std::max(level[cloth_.edges[k].a], level[cloth_.edges[k].b]);
    };
    std::stable_sort(limited.begin(), limited.end(),
                     [&](std::uint32_t l, std::uint32_t r) { return spring_level(l) < spring_level(r); });

    limit_groups_ = ColourGroups{};
    limit_groups_.group_offsets.push_back(0);
    limit_serial_.clear();
    for (std::size_t begin = 0; begin < limited.size();) {
        std::size_t end = begin;
        while (end < limited.size() && spring_level(limited[end]) == spring_level(limited[begin])) ++end;
        const ColourGroups g = colour_edges(cloth_.edges, n, std::span(limited).subspan(begin, end - begin));
        for (std::size_t k = 0; k < g.group_count(); ++k) {
            for (std::uint32_t e : g.group(k)) limit_groups_.edge_index.push_back(e);
            limit_groups_.group_offsets.push_back(static_cast<std::uint32_t>(limit_groups_.edge_index.size()));
            limit_serial_.push_back(g.is_overflow(k) ? 1 : 0);
        }
        begin = end;
    }
    limit_groups_.colour_count = static_cast<std::uint32_t>(limit_serial_.size());

    const std::size_t count = limit_groups_.edge_index.size();
    limit_a_.resize(count);
    limit_b_.resize(count);
    limit_rest_.resize(count);
    limit_inner_.resize(count);
    for (std::size_t k = 0; k < count; ++k) {
        const Edge& e = cloth_.edges[limit_groups_.edge_index[k]];
        limit_a_[k] = e.a;
        limit_b_[k] = e.b;
        limit_inner_[k] = e.kind == SpringKind::shear ? limit_shear : 0;
        limit_rest_[k] = edge_rest_.empty() ? e.rest : edge_rest_[limit_groups_.edge_index[k]];
        if (e.kind == SpringKind::seam) {
            limit_seam_slot_.push_back(static_cast<std::uint32_t>(k));
            limit_seam_edge_.push_back(limit_groups_.edge_index[k]);
        }
    }
    update_limit_levels();
}

void Simulation::limit_levels(const float* inv_mass) noexcept {
    constexpr std::uint32_t unreached = std::numeric_limits<std::uint32_t>::max();
    const std::size_t n = limit_level_.size();
    std::size_t tail = 0;
    for (std::uint32_t i = 0; i < n; ++i) {
        limit_level_[i] = inv_mass[i] == 0.0f ? 0 : unreached;
        if (inv_mass[i] == 0.0f) limit_queue_[tail++] = i;
    }
    for (std::size_t head = 0; head < tail; ++head) {
        const std::uint32_t i = limit_queue_[head];
        for (std::uint32_t k = limit_adj_offsets_[i]; k < limit_adj_offsets_[i + 1]; ++k)
            if (limit_level_[limit_adj_[k]] == unreached) {
                limit_level_[limit_adj_[k]] = limit_level_[i] + 1;
                limit_queue_[tail++] = limit_adj_[k];
            }
    }
}

void Simulation::update_limit_levels() noexcept {
    if (limit_a_.empty()) return;
    limit_levels(cloth_.inv_mass.data()); // every particle fixed now: authored pins, user pins, the grab
    for (std::size_t k = 0; k < limit_a_.size(); ++k) {
        const std::uint32_t la = limit_level_[limit_a_[k]], lb = limit_level_[limit_b_[k]];
        limit_inner_[k] = static_cast<std::uint8_t>((limit_inner_[k] & limit_shear) | (la < lb ? limit_a_inner : 0) |
                                                    (lb < la ? limit_b_inner : 0));
    }
}

template <bool Parallel> bool Simulation::strain_limit_stage(StateBuffer& out, bool with_collide) {
    const StrainLimit& sl = params_.strain_limit;
    if (sl.ratio <= 0.0f || limit_a_.empty() || (steps_done_ + 1) % sl.every != 0) return false;
    // The implicit solver's form (one-sided, no shear, positions only: above) except while a grab is held, when the
    // explicit solver's form runs (a drag out of the cloth's reach: the one-sided form put its whole excess into the
    // spring next to the grab; the mass-weighted form without shear springs and velocities let the stretch creep up
    // over 20 steps of the NoAllocation grab at N = 48; the full explicit form holds there, as it always did).
    const bool frame_form = strain_limit_frame_form();
    LimitArgs c{out.x.data(), out.y.data(), out.z.data(), out.u.data(), out.v.data(), out.w.data(),
                cloth_.inv_mass.data(), limit_a_.data(), limit_b_.data(), limit_rest_.data(),
                frame_form ? limit_inner_.data() : nullptr, frame_form, 1.0f + sl.ratio, 1.0f + 1.05f * sl.ratio,
                frame_form ? 0.0f
                : params_.integrator == Integrator::symplectic_euler ? 1.0f / (float(sl.every) * params_.dt)
                                                                     : 1.0f / float(sl.every)};
    // At least `passes` sweeps; more (up to strain_limit_max_passes) while a sweep still found a spring over
    // 1.05 x the limit, so a limit that can hold does (the JSON of `drape run` reports what was honoured).
    for (std::uint32_t pass = 0; pass < strain_limit_max_passes; ++pass) {
        std::atomic<bool> over{false}; // an OR: the same whatever the order of the chunks
        for (std::size_t g = 0; g < limit_groups_.group_count(); ++g) {
            const std::size_t begin = limit_groups_.group_offsets[g], end = limit_groups_.group_offsets[g + 1];
            const std::size_t chunks = (end - begin + limit_chunk - 1) / limit_chunk;
            if (Parallel && !limit_serial_[g] && chunks > 1) {
                tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t ch) {
                    if (limit_range(c, begin + ch * limit_chunk, std::min(end, begin + (ch + 1) * limit_chunk)))
                        over.store(true, std::memory_order_relaxed);
                });
            } else if (limit_range(c, begin, end)) { // small group, serial twin, or the overflow group
                over.store(true, std::memory_order_relaxed);
            }
        }
        // Collide after each sweep; its triangle pass after the first sweep and the last but one of the `passes`
        // (the triangle pass costs more than a sweep), so the limit has the last sweep and the sweeps between.
        const std::uint32_t last_but_one = std::max<std::uint32_t>(sl.passes, 2) - 2;
        const bool triangles = pass == 0 || pass == last_but_one;
        if (with_collide) collide_stage<Parallel>(out, true, triangles ? 1 : 0);
        if (pass + 1 >= sl.passes && !over.load(std::memory_order_relaxed)) break;
    }
    return true;
}

template bool Simulation::strain_limit_stage<true>(StateBuffer&, bool);
template bool Simulation::strain_limit_stage<false>(StateBuffer&, bool);

} // namespace drape
