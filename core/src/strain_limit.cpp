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
// pins carries its whole weight outward from them). So the springs are levelled by breadth-first distance over the
// structural and seam springs from the authored pins (level of a spring = the larger level of its ends), coloured
// level by level and processed from the pins outward: each pass carries a correction from the pins to the free edge.
// A cloth without pins has a single level. User pins and grabs (inverse mass 0) keep their ends fixed.
// With colliders, Simulation::step interleaves: sweep, collide, sweep, collide, ... (collide last), so a particle a
// collider pushed out is limited again and no particle ends a substep inside a collider.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <span>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "drape/mirror_symmetry.hpp"
#include "drape/simulation.hpp"
#include "for_each_index.hpp"
#include "strain_limit_sweep.hpp"

namespace drape {

namespace {

/// Springs per parallel chunk of a colour group (fixed: the partition never depends on the thread count).
constexpr std::size_t limit_chunk = 4096;

} // namespace

void Simulation::cook_strain_limit() {
    if (!limit_a_.empty() || cloth_.edges.empty()) return;
    const std::size_t n = cloth_.particle_count;
    std::vector<std::uint32_t> limited;
    for (std::uint32_t k = 0; k < cloth_.edges.size(); ++k)
        if (cloth_.edges[k].kind != SpringKind::bend) limited.push_back(k);

    // Adjacency over the limited springs but the shear springs (kept: update_limit_levels walks it again when pins or
    // grabs change). Levels are then structural (on a grid: row plus column) distances from the pins, so the two ends
    // of every structural spring have different levels and the frame form moves the outer one. Counting shear springs
    // made the levels king-move distances: along a row within a clip's square every particle had the same level, the
    // springs between them moved both ends, their corrections crept along the row sweep by sweep, and at N = 316 and
    // 1000 the limit's 100 sweeps left every other spring of those rows over it (0.104 and 0.206 at 0.9 s of the wool
    // hang; docs/implicit.md, "Compression next to the clips").
    std::vector<std::uint32_t>& adj_offsets = limit_adj_offsets_;
    std::vector<std::uint32_t>& adj = limit_adj_;
    const auto levelled = [&](std::uint32_t k) { return cloth_.edges[k].kind != SpringKind::shear; };
    adj_offsets.assign(n + 1, 0);
    for (std::uint32_t k : limited) {
        if (!levelled(k)) continue;
        ++adj_offsets[cloth_.edges[k].a + 1];
        ++adj_offsets[cloth_.edges[k].b + 1];
    }
    for (std::size_t i = 0; i < n; ++i) adj_offsets[i + 1] += adj_offsets[i];
    adj.resize(adj_offsets[n]);
    {
        std::vector<std::uint32_t> fill(adj_offsets.begin(), adj_offsets.end() - 1);
        for (std::uint32_t k : limited) {
            if (!levelled(k)) continue;
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

    // A mirror-exact cloth (mirror_symmetry.hpp): each spring coloured with its mirror image, so that the sweeps
    // treat the halves alike, when every mirror pair of springs is on one level (pins placed mirror-symmetrically).
    std::vector<std::uint32_t> edge_twin;
    if (!cloth_.mirror.empty()) {
        edge_twin = mirror_edge_map(cloth_.edges, cloth_.mirror);
        for (std::uint32_t k : limited)
            if (spring_level(edge_twin[k]) != spring_level(k)) {
                edge_twin.clear();
                break;
            }
    }
    limit_groups_ = ColourGroups{};
    limit_groups_.group_offsets.push_back(0);
    limit_serial_.clear();
    limit_shear_begin_.clear();
    for (std::size_t begin = 0; begin < limited.size();) {
        std::size_t end = begin;
        while (end < limited.size() && spring_level(limited[end]) == spring_level(limited[begin])) ++end;
        const ColourGroups g = colour_edges(cloth_.edges, n, std::span(limited).subspan(begin, end - begin),
                                            colouring_max_colours, edge_twin);
        for (std::size_t k = 0; k < g.group_count(); ++k) {
            // Shear springs last (no two springs of a colour group share a particle, so the order within one does
            // not change the result; an overflow group keeps its order by running whole in either form).
            const auto shear = [&](std::uint32_t e) { return cloth_.edges[e].kind == SpringKind::shear; };
            for (std::uint32_t e : g.group(k))
                if (g.is_overflow(k) || !shear(e)) limit_groups_.edge_index.push_back(e);
            limit_shear_begin_.push_back(static_cast<std::uint32_t>(limit_groups_.edge_index.size()));
            if (!g.is_overflow(k))
                for (std::uint32_t e : g.group(k))
                    if (shear(e)) limit_groups_.edge_index.push_back(e);
            limit_groups_.group_offsets.push_back(static_cast<std::uint32_t>(limit_groups_.edge_index.size()));
            limit_serial_.push_back(g.is_overflow(k) ? 1 : 0);
        }
        begin = end;
    }
    limit_groups_.colour_count = static_cast<std::uint32_t>(limit_serial_.size());
    // Per particle, the groups holding one of its springs (each once, ascending).
    limit_particle_group_offsets_.assign(n + 1, 0);
    limit_particle_groups_.clear();
    {
        std::vector<std::vector<std::uint32_t>> groups_of(n);
        for (std::uint32_t g = 0; g < limit_groups_.group_count(); ++g)
            for (std::uint32_t e : limit_groups_.group(g))
                for (std::uint32_t i : {cloth_.edges[e].a, cloth_.edges[e].b})
                    if (groups_of[i].empty() || groups_of[i].back() != g) groups_of[i].push_back(g);
        for (std::size_t i = 0; i < n; ++i) {
            limit_particle_groups_.insert(limit_particle_groups_.end(), groups_of[i].begin(), groups_of[i].end());
            limit_particle_group_offsets_[i + 1] = static_cast<std::uint32_t>(limit_particle_groups_.size());
        }
    }
    limit_group_moved_.assign(limit_groups_.group_count(), 0);
    limit_px_.assign(n, 0.0f);
    limit_py_.assign(n, 0.0f);
    limit_pz_.assign(n, 0.0f);

    const std::size_t count = limit_groups_.edge_index.size();
    limit_a_.resize(count);
    limit_b_.resize(count);
    limit_rest_.resize(count);
    limit_inner_.resize(count);
    for (std::size_t k = 0; k < count; ++k) {
        const Edge& e = cloth_.edges[limit_groups_.edge_index[k]];
        limit_a_[k] = e.a;
        limit_b_[k] = e.b;
        limit_inner_[k] = e.kind == SpringKind::shear  ? strain_limit::shear
                          : e.kind == SpringKind::seam ? strain_limit::seam
                                                       : 0;
        limit_rest_[k] = edge_rest_.empty() ? e.rest : edge_rest_[limit_groups_.edge_index[k]];
        if (e.kind == SpringKind::seam) {
            limit_seam_slot_.push_back(static_cast<std::uint32_t>(k));
            limit_seam_edge_.push_back(limit_groups_.edge_index[k]);
        }
    }
    // The two springs of a mirror pair that meet at a particle on the mirror line (adjacent in their group: the
    // only two springs of a conflict-free group that share a particle) are solved together.
    limit_pair_.clear();
    if (!edge_twin.empty()) {
        limit_pair_.assign(count, 0);
        const auto shares = [&](std::size_t k) {
            return limit_a_[k] == limit_a_[k + 1] || limit_a_[k] == limit_b_[k + 1] || limit_b_[k] == limit_a_[k + 1] ||
                   limit_b_[k] == limit_b_[k + 1];
        };
        for (std::uint32_t g = 0; g < limit_groups_.group_count(); ++g) {
            if (limit_serial_[g]) continue;
            for (const auto& [lo, hi] : {std::pair{limit_groups_.group_offsets[g], limit_shear_begin_[g]},
                                        std::pair{limit_shear_begin_[g], limit_groups_.group_offsets[g + 1]}})
                for (std::size_t k = lo; k + 1 < hi; ++k)
                    if (shares(k)) limit_pair_[k] = strain_limit::pair_first, limit_pair_[++k] = strain_limit::pair_second;
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
        constexpr std::uint32_t unreached = std::numeric_limits<std::uint32_t>::max();
        limit_inner_[k] = static_cast<std::uint8_t>((limit_inner_[k] & (strain_limit::shear | strain_limit::seam)) |
                                                    (la < lb ? strain_limit::a_inner : 0) |
                                                    (lb < la ? strain_limit::b_inner : 0) |
                                                    (la == unreached ? strain_limit::unpinned : 0));
    }
}

template <bool Parallel> bool Simulation::strain_limit_stage(StateBuffer& out, bool with_collide) {
    const StrainLimit& sl = params_.strain_limit;
    limit_over_ = false;
    if (sl.ratio <= 0.0f || limit_a_.empty() || (steps_done_ + 1) % sl.every != 0) return false;
    // The implicit solver's form (one-sided, no shear, velocities for two-sided moves only), a grab held or not. Until
    // 2026-11-30 a grab switched to the explicit solver's form (a drag out of the cloth's reach had put the whole
    // excess into the spring next to the grab, before the levels by structural springs and both ends moving after 50
    // sweeps); that form's shear corrections squeezed the cloth around a grab held in place (|strain| 0.31 at N = 100,
    // 0.41 at N = 300 with the limit at 0.1, and a 300 x 300 hang grabbed in the viewer blew up) where this form holds
    // 0.100 (docs/implicit.md, "A held particle in the middle").
    const bool frame_form = strain_limit_frame_form();
    strain_limit::Args c{out.x.data(),
                         out.y.data(),
                         out.z.data(),
                         out.u.data(),
                         out.v.data(),
                         out.w.data(),
                         cloth_.inv_mass.data(),
                         limit_a_.data(),
                         limit_b_.data(),
                         limit_rest_.data(),
                         frame_form ? limit_inner_.data() : nullptr,
                         1.0f + sl.ratio,
                         1.0f + strain_limit_tolerance * sl.ratio,
                         frame_form ? std::max(0.0f, 1.0f - sl.ratio) : 0.0f,
                         frame_form ? std::max(0.0f, 1.0f - strain_limit_tolerance * sl.ratio) : 0.0f,
                         frame_form || params_.integrator == Integrator::symplectic_euler
                             ? 1.0f / (float(sl.every) * params_.dt)
                             : 1.0f / float(sl.every),
                         limit_particle_group_offsets_.data(),
                         limit_particle_groups_.data(),
                         limit_group_moved_.data()};
    c.pair = limit_pair_.empty() ? nullptr : limit_pair_.data();
    const std::size_t groups = limit_groups_.group_count();
    const std::size_t n = cloth_.particle_count;
    if (frame_form)
        for_each_index<Parallel>(cloth_.block_count(), [&](std::size_t blk) {
            const std::size_t begin = blk * block_particles, end = std::min(n, begin + block_particles);
            std::copy(out.x.begin() + begin, out.x.begin() + end, limit_px_.begin() + begin);
            std::copy(out.y.begin() + begin, out.y.begin() + end, limit_py_.begin() + begin);
            std::copy(out.z.begin() + begin, out.z.begin() + end, limit_pz_.begin() + begin);
        });
    // At least `passes` sweeps; more (up to strain_limit_max_passes) while a sweep still found a spring over
    // 1.05 x the limit, so a limit that can hold does (the JSON of `drape run` reports what was honoured).
    for (std::uint32_t pass = 0; pass < strain_limit_max_passes; ++pass) {
        c.one_sided = pass < strain_limit_one_sided_passes;
        std::atomic<bool> over{false}; // an OR: the same whatever the order of the chunks
        for (std::size_t g = 0; g < groups; ++g) {
            const std::uint64_t seq = ++limit_seq_;
            const std::size_t begin = limit_groups_.group_offsets[g];
            const std::size_t end = frame_form ? limit_shear_begin_[g] : limit_groups_.group_offsets[g + 1];
            if (begin == end) continue;
            // Nothing in the group moved since this group's sweep one pass ago (the collider pass, run between
            // sweeps, moves particles without stamps): its springs are as that sweep left them, none over the limit.
            if (pass > 0 && !with_collide && limit_group_moved_[g] < seq - groups) continue;
            const std::size_t chunks = (end - begin + limit_chunk - 1) / limit_chunk;
            if (limit_serial_[g]) { // the overflow group: its springs may share particles, so in order
                if (strain_limit::sweep(c, begin, end, seq)) over.store(true, std::memory_order_relaxed);
            } else if (Parallel && chunks > 1) {
                tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t ch) {
                    if (strain_limit::sweep(c, begin + ch * limit_chunk, std::min(end, begin + (ch + 1) * limit_chunk),
                                            seq))
                        over.store(true, std::memory_order_relaxed);
                });
            } else if (strain_limit::sweep(c, begin, end, seq)) { // a small group, or the serial twin
                over.store(true, std::memory_order_relaxed);
            }
        }
        // Collide after each sweep; its triangle pass after the first sweep and the last but one of the `passes`
        // (the triangle pass costs more than a sweep), so the limit has the last sweep and the sweeps between.
        const std::uint32_t last_but_one = std::max<std::uint32_t>(sl.passes, 2) - 2;
        const bool triangles = pass == 0 || pass == last_but_one;
        if (with_collide) collide_stage<Parallel>(out, true, triangles ? 1 : 0);
        limit_over_ = over.load(std::memory_order_relaxed);
        if (pass + 1 >= sl.passes && !limit_over_) break;
    }
    // A limit that could not hold (the implicit solver's form: positions only where a fixed particle is connected):
    // each particle it moved loses the velocity against its move, as a collider's contact loses the velocity into it.
    // Otherwise the next step's inertial prediction carried the cloth out again by what the limit had taken back, and
    // the limit pulled it in again, every step: the tank top dragged by its hem 28 cm forward (the body holding it
    // back, so the limit at 0.1 cannot hold) gained 7.8 J in 1.7 s, against 0.009 J with the explicit solver, and put
    // 19 triangles into the body (docs/implicit.md, "A limit that cannot hold"). Only velocity is removed: no energy is
    // added, and where the limit holds nothing changes.
    if (frame_form && limit_over_)
        for_each_index<Parallel>(cloth_.block_count(), [&](std::size_t blk) {
            const std::size_t begin = blk * block_particles, end = std::min(n, begin + block_particles);
            for (std::size_t i = begin; i < end; ++i) {
                const float dx = out.x[i] - limit_px_[i], dy = out.y[i] - limit_py_[i], dz = out.z[i] - limit_pz_[i];
                const float d2 = dx * dx + dy * dy + dz * dz;
                if (!(d2 > 0.0f)) continue;
                const float vd = out.u[i] * dx + out.v[i] * dy + out.w[i] * dz;
                if (!(vd < 0.0f)) continue;
                const float s = vd / d2;
                out.u[i] -= s * dx;
                out.v[i] -= s * dy;
                out.w[i] -= s * dz;
            }
        });
    return true;
}

template bool Simulation::strain_limit_stage<true>(StateBuffer&, bool);
template bool Simulation::strain_limit_stage<false>(StateBuffer&, bool);

} // namespace drape
