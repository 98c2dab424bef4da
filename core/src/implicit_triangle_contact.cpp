// Triangle contact inside the implicit solve (docs/implicit.md, "Triangle contact inside the solve").
//
// The collide stage's triangle pass (collide.cpp) pushes a triangle whose inside reaches into a collider out
// at its deepest point after the step. After an implicit step that push was all the triangle's contact there
// was: across a disc's rim it stretched the springs over the rim, and the next step's sweeps pulled them back
// in (the drape scene without its strain limit: 0.2-0.5 strain at the rim for good). Here the contact enters
// the step's objective: at the step's start (x^n, which the last step left clear of the colliders) each
// triangle whose inside is within a search reach of a solid collider's inflated surface gets a term on the
// material point q = sum b_j x_j that was deepest then, with the energy k / 2 min(0, phi(q))^2 (phi: q's
// signed distance to the inflated surface, evaluated again at every local step) and Coulomb friction on q's
// move; every vertex of the triangle adds it to its local step (vbd::triangle_terms_step). The triangle pass
// after the step then finds what the penalty leaves.
//
// Per triangle in parallel, each writing its own record; then per particle, whether any of its triangles has
// one. No write is shared: the same bits for every thread count. No allocation (cooked with the triangle
// pass).
#include "drape/simulation.hpp"

#include <algorithm>
#include <limits>

#include "drape/triangle_contact.hpp"
#include "for_each_index.hpp"
#include "implicit_solver.hpp"
#include "triangle_contact_search.hpp"
#include "vbd.hpp"

namespace drape {

namespace {
/// The terms' stiffness: this many times the largest sum of spring stiffnesses at the triangle's vertices (a
/// vertex's springs hold it with about that sum, so the contact's residual depth is about a spring's strain
/// times the spacing).
constexpr float triangle_term_stiffness = 4.0f;
/// How far beyond a collider's thickness a triangle gets a term, in cloth spacings: the step moves the cloth
/// from x^n, and a term the free step does not break is inactive.
constexpr float triangle_term_reach = 1.0f;
/// A deepest point this close to a vertex (largest barycentric weight above 1 - this) is the vertex's own
/// contact, which the sweeps keep already (vbd::contact_project, with its friction): no term (a cloth lying
/// on a disc's top has such a triangle at every vertex; their terms cost 1.6x the step and changed nothing
/// measured).
constexpr float vertex_contact_weight = 1e-3f;
} // namespace

void Simulation::cook_triangle_terms() {
    const std::size_t tris = cloth_.triangles.size() / 3, n = cloth_.particle_count;
    if (tt_on_.size() != tris) {
        tt_on_.assign(tris, 0);
        tt_term_.assign(tris * vbd::triangle_term_floats, 0.0f);
    }
    if (tt_vertex_on_.size() != n) tt_vertex_on_.assign(n, 0);
    tt_reach_ = triangle_term_reach * static_cast<float>(cloth_spacing(cloth_));
    tt_colliders_ = params_.colliders;
    for (Collider& c : tt_colliders_)
        c.thickness += tt_reach_;
}

template <bool Parallel>
bool Simulation::implicit_triangle_terms(const float* x, const float* y, const float* z) {
    const std::size_t tris = tt_on_.size(), n = cloth_.particle_count;
    if (tris == 0 || tt_colliders_.size() != params_.colliders.size()) return false;
    bool any_solid = false;
    for (const Collider& col : tt_colliders_)
        any_solid = any_solid || col.kind != ColliderKind::plane;
    if (!any_solid || core_measure_.size() != n * tt_colliders_.size()) return false;
    // A mirror-exact cloth's triangles in mirror corner order (make_mirror_exact), as the collide stage's pass reads them.
    const std::uint32_t* tri = cloth_.mirror_corners.empty() ? cloth_.triangles.data() : cloth_.mirror_corners.data();
    const float* w = cloth_.inv_mass.data();
    const VbdGraph& graph = implicit_->fine.graph();
    float* clear = clearance_.data();
    float* measure = core_measure_.data();
    const std::span<const Collider> grown(tt_colliders_);
    for_each_index<Parallel>((n + block_particles - 1) / block_particles, [&](std::size_t blk) {
        const std::size_t begin = blk * block_particles, end = std::min(begin + block_particles, n);
        detail::triangle_contact_bounds(grown, n, x, y, z, clear, measure, begin, end);
    });
    auto stiffness = [&](std::uint32_t i) {
        float s = 0.0f;
        for (std::uint32_t k = graph.spring_offsets[i]; k < graph.spring_offsets[i + 1]; ++k)
            s += graph.spring_k[k];
        return s;
    };
    // The projections' warm starts (vbd::TriangleTerms::warm): a triangle is projected by each of its corners in
    // turn, one colour after another, so a colour touches it once (and one thread), provided its three corners have
    // three colours. The greedy colouring gives that where a triangle's edges are springs, except on a mirror-exact
    // cloth with a triangle joining a particle to its own twin (the pair shares a colour); checked once, and any
    // triangle without three colours turns the warm starts off for the cloth.
    if (!tt_warm_checked_) {
        tt_warm_checked_ = true;
        std::vector<std::uint32_t> colour(n, 0);
        for (std::size_t c = 0; c < graph.colour_count(); ++c)
            for (std::uint32_t k = graph.colour_offsets[c]; k < graph.colour_offsets[c + 1]; ++k)
                colour[graph.colour_vertex[k]] = static_cast<std::uint32_t>(c);
        bool distinct = true;
        for (std::size_t t = 0; t < tris && distinct; ++t) {
            const std::uint32_t c0 = colour[tri[3 * t]], c1 = colour[tri[3 * t + 1]], c2 = colour[tri[3 * t + 2]];
            distinct = c0 != c1 && c1 != c2 && c0 != c2;
        }
        if (distinct) {
            tt_warm_.assign(tris, 0.0f);
            tt_plane_.assign(tris * vbd::triangle_plane_floats, 0.0f);
        }
    }
    float* warm = tt_warm_.empty() ? nullptr : tt_warm_.data();
    float* plane = tt_plane_.empty() ? nullptr : tt_plane_.data();
    constexpr std::size_t tri_block = 256;
    std::vector<std::uint8_t>& on = tt_on_;
    float* term = tt_term_.data();
    for_each_index<Parallel>((tris + tri_block - 1) / tri_block, [&](std::size_t blk) {
        for (std::size_t t = blk * tri_block, end = std::min(tris, (blk + 1) * tri_block); t < end; ++t) {
            on[t] = 0;
            if (warm) warm[t] = 0.0f;
            if (plane) plane[vbd::triangle_plane_floats * t + 6] = std::numeric_limits<float>::quiet_NaN();
            const std::uint32_t v[3] = {tri[3 * t], tri[3 * t + 1], tri[3 * t + 2]};
            if (w[v[0]] == 0.0f && w[v[1]] == 0.0f && w[v[2]] == 0.0f) continue;
            TriangleContact best;
            float mu = 0.0f;
            std::size_t k = 0;
            if (!detail::deepest_triangle_contact(grown, n, v, x, y, z, clear, measure, best, mu, tt_reach_,
                                                  &k))
                continue;
            const float* b = best.barycentric.data();
            if (std::max({b[0], b[1], b[2]}) > 1.0f - vertex_contact_weight) continue;
            float* e = term + t * vbd::triangle_term_floats;
            e[0] = b[0];
            e[1] = b[1];
            e[2] = b[2];
            e[3] = triangle_term_stiffness * std::max({stiffness(v[0]), stiffness(v[1]), stiffness(v[2])});
            e[4] = mu;
            on[t] = static_cast<std::uint8_t>(k + 1); // at most 64 colliders (check_params)
        }
    });
    for_each_index<Parallel>((n + block_particles - 1) / block_particles, [&](std::size_t blk) {
        for (std::size_t i = blk * block_particles, end = std::min(n, (blk + 1) * block_particles); i < end;
             ++i) {
            std::uint8_t f = 0;
            for (std::uint32_t k = vertex_tri_offsets_[i]; k < vertex_tri_offsets_[i + 1]; ++k)
                f |= on[vertex_tris_[k]] != 0;
            tt_vertex_on_[i] = f;
        }
    });
    return std::any_of(on.begin(), on.end(), [](std::uint8_t c) { return c != 0; });
}

template bool Simulation::implicit_triangle_terms<true>(const float*, const float*, const float*);
template bool Simulation::implicit_triangle_terms<false>(const float*, const float*, const float*);

} // namespace drape
