// Cooking for vertex block descent: per-vertex springs (CSR), bending rows in float, and a greedy vertex colouring.
#include "vbd.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <tuple>

#include "drape/mirror_symmetry.hpp"
#include "for_each_index.hpp"
#include "vbd_batch.hpp"
#include "vbd_grid.hpp"

namespace drape::vbd {

void refresh_materials(VbdGraph& g, const Cloth& cloth) {
    for (std::size_t e = 0; e < g.spring_edge.size(); ++e) {
        const Edge& edge = cloth.edges[g.spring_edge[e]];
        const SpringMaterial& m = cloth.material[static_cast<std::size_t>(edge.kind)];
        g.spring_k[e] = m.stiffness * edge.scale;
        g.spring_kd[e] = m.damping * edge.scale;
    }
}

namespace {

VbdGraph finish_colouring(VbdGraph& g, const std::vector<std::uint32_t>& colour, std::uint32_t colours,
                          const std::vector<std::uint32_t>& pair_of = {});

/// P = 2 or 3 when the cloth is a full grid and no spring or bending entry joins two vertices of one class
/// (row mod P, column mod P); 0 otherwise.
std::uint32_t grid_period(const Cloth& cloth, const VbdGraph& g) {
    const std::size_t n = g.particle_count;
    if (!cloth.grid || std::size_t(cloth.grid->rows) * cloth.grid->columns != n) return 0;
    const std::uint32_t columns = cloth.grid->columns;
    for (std::uint32_t P : {2u, 3u}) {
        auto same_class = [&](std::size_t i, std::uint32_t j) {
            return (i / columns) % P == (j / columns) % P && (i % columns) % P == (j % columns) % P;
        };
        bool fits = true;
        for (std::size_t i = 0; i < n && fits; ++i) {
            for (std::uint32_t e = g.spring_offsets[i]; e < g.spring_offsets[i + 1] && fits; ++e)
                fits = !same_class(i, g.spring_neighbour[e]);
            if (!g.bend_offsets.empty())
                for (std::uint32_t e = g.bend_offsets[i]; e < g.bend_offsets[i + 1] && fits; ++e)
                    fits = !same_class(i, g.bend_neighbour[e]);
        }
        if (fits) return P;
    }
    return 0;
}

} // namespace

std::vector<std::uint32_t> mirror_twins(std::span<const float> x, std::span<const float> y, std::span<const float> z) {
    const std::size_t n = x.size();
    if (n == 0 || y.size() != n || z.size() != n) return {};
    const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
    const double mid = 0.5 * (double(*lo) + double(*hi));
    constexpr double tol = 1e-5;
    // Particles by (y, z, |x - mid|) rounded to the tolerance; a twin is looked for in the 27 neighbouring keys.
    auto cell = [&](double v) { return std::int64_t(std::floor(v / tol)); };
    using Key = std::array<std::int64_t, 3>;
    std::vector<std::pair<Key, std::uint32_t>> bins(n);
    for (std::uint32_t i = 0; i < n; ++i) bins[i] = {{cell(y[i]), cell(z[i]), cell(std::abs(x[i] - mid))}, i};
    std::sort(bins.begin(), bins.end());
    std::vector<std::uint32_t> twin(n, UINT32_MAX);
    std::size_t found = 0;
    for (std::uint32_t i = 0; i < n; ++i) {
        const double mx = 2.0 * mid - double(x[i]);
        if (std::abs(double(x[i]) - mid) <= tol) {
            twin[i] = i, ++found;
            continue;
        }
        const std::array<std::int64_t, 3> k = {cell(y[i]), cell(z[i]), cell(std::abs(x[i] - mid))};
        double best = tol;
        for (int a = -1; a <= 1; ++a)
            for (int b = -1; b <= 1; ++b)
                for (int c = -1; c <= 1; ++c) {
                    const Key key = {k[0] + a, k[1] + b, k[2] + c};
                    auto it = std::lower_bound(bins.begin(), bins.end(), std::pair<Key, std::uint32_t>{key, 0u});
                    for (; it != bins.end() && it->first == key; ++it) {
                        const std::uint32_t j = it->second;
                        if (j == i) continue;
                        const double d = std::max({std::abs(double(x[j]) - mx), std::abs(double(y[j]) - double(y[i])),
                                                   std::abs(double(z[j]) - double(z[i]))});
                        if (d <= best) best = d, twin[i] = j;
                    }
                }
        if (twin[i] != UINT32_MAX) ++found;
    }
    // Twins must be mutual.
    for (std::uint32_t i = 0; i < n; ++i)
        if (twin[i] != UINT32_MAX && twin[twin[i]] != i) twin[i] = UINT32_MAX;
    found = std::size_t(std::count_if(twin.begin(), twin.end(), [](std::uint32_t t) { return t != UINT32_MAX; }));
    if (double(found) < 0.95 * double(n)) return {};
    return twin;
}

VbdGraph cook(const Cloth& cloth, std::span<const std::uint32_t> twin) {
    const std::size_t n = cloth.particle_count;
    VbdGraph g;
    g.particle_count = n;

    // Springs: both directions of every edge, rows sorted by neighbour.
    g.spring_offsets.assign(n + 1, 0);
    for (const Edge& e : cloth.edges) {
        ++g.spring_offsets[e.a + 1];
        ++g.spring_offsets[e.b + 1];
    }
    std::partial_sum(g.spring_offsets.begin(), g.spring_offsets.end(), g.spring_offsets.begin());
    const std::size_t entries = g.spring_offsets[n];
    g.spring_neighbour.resize(entries);
    g.spring_edge.resize(entries);
    std::vector<std::uint32_t> fill(g.spring_offsets.begin(), g.spring_offsets.end() - 1);
    for (std::uint32_t k = 0; k < cloth.edges.size(); ++k) {
        const Edge& e = cloth.edges[k];
        g.spring_neighbour[fill[e.a]] = e.b;
        g.spring_edge[fill[e.a]++] = k;
        g.spring_neighbour[fill[e.b]] = e.a;
        g.spring_edge[fill[e.b]++] = k;
    }
    std::vector<std::pair<std::uint32_t, std::uint32_t>> row;
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint32_t b = g.spring_offsets[i], end = g.spring_offsets[i + 1];
        row.clear();
        for (std::uint32_t e = b; e < end; ++e) row.emplace_back(g.spring_neighbour[e], g.spring_edge[e]);
        std::sort(row.begin(), row.end());
        for (std::uint32_t e = b; e < end; ++e) {
            g.spring_neighbour[e] = row[e - b].first;
            g.spring_edge[e] = row[e - b].second;
        }
    }
    // A mirror-exact cloth (Cloth::mirror, then also the twin map): each row in mirror order, so that a particle
    // and its twin take their terms in the same order and a particle on the mirror plane takes each next to its
    // mirror image's.
    g.mirror_exact = !cloth.mirror.empty();
    if (g.mirror_exact) {
        const std::vector<std::uint32_t> from =
            mirror_row_sources(g.spring_offsets, g.spring_neighbour, cloth.mirror, cloth.mirror);
        g.spring_neighbour = gather(g.spring_neighbour, from);
        g.spring_edge = gather(g.spring_edge, from);
    }
    g.spring_k.resize(entries);
    g.spring_kd.resize(entries);
    g.spring_rest.resize(entries);
    for (std::size_t e = 0; e < entries; ++e) g.spring_rest[e] = cloth.edges[g.spring_edge[e]].rest;
    refresh_materials(g, cloth);

    // Bending rows from the cooked Q (double) into float.
    const BendingSet& bend = cloth.bending;
    if (!bend.empty()) {
        g.bend_offsets = bend.offsets;
        g.bend_neighbour = bend.neighbour;
        std::vector<double> value = bend.value;
        if (g.mirror_exact) {
            // mirror_row_order reads sorted rows: sort each (neighbour, value), then put it in mirror order.
            for (std::size_t i = 0; i < n; ++i) {
                std::vector<std::pair<std::uint32_t, double>> row;
                for (std::uint32_t e = g.bend_offsets[i]; e < g.bend_offsets[i + 1]; ++e)
                    row.emplace_back(g.bend_neighbour[e], value[e]);
                std::sort(row.begin(), row.end());
                for (std::uint32_t e = g.bend_offsets[i]; e < g.bend_offsets[i + 1]; ++e)
                    std::tie(g.bend_neighbour[e], value[e]) = row[e - g.bend_offsets[i]];
            }
            const std::vector<std::uint32_t> from =
                mirror_row_sources(g.bend_offsets, g.bend_neighbour, cloth.mirror, cloth.mirror);
            g.bend_neighbour = gather(g.bend_neighbour, from);
            value = gather(value, from);
        }
        g.bend_q.resize(value.size());
        g.bend_diag.assign(n, 0.0f);
        for (std::size_t i = 0; i < n; ++i) {
            double diag = 0.0;
            for (std::uint32_t e = g.bend_offsets[i]; e < g.bend_offsets[i + 1]; ++e) {
                g.bend_q[e] = static_cast<float>(value[e]);
                diag -= value[e];
            }
            g.bend_diag[i] = static_cast<float>(diag);
        }
        g.bend_beta = bend.damping;
    }

    // A full grid cloth none of whose couplings joins two vertices of one class (row mod P, column mod P), P = 2 or 3
    // (grid_period): the colours are the classes, so that the sweeps can run on colour sub-grids (vbd_grid.hpp). Other cloths: greedy colouring in index order, each vertex taking the smallest colour none of
    // its coupled neighbours (springs or bending) has yet.
    std::vector<std::uint32_t> colour(n, UINT32_MAX);
    const std::uint32_t period = grid_period(cloth, g);
    if (period != 0) {
        const std::uint32_t columns = cloth.grid->columns;
        std::vector<std::uint32_t> class_colour(period * period, UINT32_MAX);
        for (std::uint32_t i = 0; i < n; ++i)
            class_colour[((i / columns) % period) * period + (i % columns) % period] = 0;
        // Colour order: the classes by diagonal, (column - row) mod P, then by row: (0,0) (1,1) (2,2) (0,1) (1,2) (2,0)
        // (0,2) (1,0) (2,1) for P = 3. In row-major class order the 40 x 40 canvas of
        // Implicit.LargeStepsOnStiffFabricStayFinite reached strain 0.80 at h = 0.1 s (8 iterations), 0.30 in this
        // order, 0.39 with the greedy colouring.
        std::vector<std::uint32_t> order(period * period);
        std::iota(order.begin(), order.end(), 0u);
        std::stable_sort(order.begin(), order.end(), [&](std::uint32_t l, std::uint32_t r) {
            auto key = [&](std::uint32_t c) { return ((c % period) + period - c / period) % period; };
            return key(l) < key(r);
        });
        std::uint32_t colours = 0;
        for (std::uint32_t k : order)
            if (class_colour[k] == 0) class_colour[k] = colours++;
        for (std::uint32_t i = 0; i < n; ++i)
            colour[i] = class_colour[((i / columns) % period) * period + (i % columns) % period];
        return finish_colouring(g, colour, colours);
    }
    // With mirror twins (a symmetric garment) each particle is coloured together with its twin, both taking the
    // smallest colour free at either: the sweeps then visit mirror images in the same colour, so a symmetric cloth
    // stays symmetric to rounding (in index order the T-shirt's halves were swept in unrelated orders and settled
    // ~1 cm apart). A twin coupled to its particle (across the mirror plane) takes its own colour after it.
    const std::span<const std::uint32_t> twin_of = g.mirror_exact ? std::span<const std::uint32_t>(cloth.mirror) : twin;
    const bool paired = twin_of.size() == n;
    std::vector<std::uint32_t> pair_of(g.mirror_exact ? n : 0, UINT32_MAX); // i < t coupled, same colour: t
    std::vector<std::uint32_t> stamp; // stamp[c] == tag: colour c is taken by a neighbour of the particle(s) tagged
    std::uint32_t colours = 0, tag = 0;
    auto mark_neighbours = [&](std::uint32_t i) {
        auto mark = [&](std::uint32_t j) {
            const std::uint32_t c = colour[j];
            if (c == UINT32_MAX) return;
            if (c >= stamp.size()) stamp.resize(c + 1, 0);
            stamp[c] = tag;
        };
        for (std::uint32_t e = g.spring_offsets[i]; e < g.spring_offsets[i + 1]; ++e) mark(g.spring_neighbour[e]);
        if (!bend.empty())
            for (std::uint32_t e = bend.offsets[i]; e < bend.offsets[i + 1]; ++e) mark(bend.neighbour[e]);
    };
    auto smallest_free = [&] {
        std::uint32_t c = 0;
        while (c < stamp.size() && stamp[c] == tag) ++c;
        return c;
    };
    auto give = [&](std::uint32_t i, std::uint32_t c) {
        colour[i] = c;
        colours = std::max(colours, c + 1);
    };
    for (std::uint32_t i = 0; i < n; ++i) {
        if (colour[i] != UINT32_MAX) continue; // a twin coloured with its particle
        const std::uint32_t t = paired ? twin_of[i] : UINT32_MAX;
        ++tag;
        mark_neighbours(i);
        if (t == UINT32_MAX || t == i || colour[t] != UINT32_MAX) {
            give(i, smallest_free());
            continue;
        }
        mark_neighbours(t);
        const std::uint32_t c = smallest_free();
        give(i, c);
        // The twin takes c too unless it is coupled to i (c is taken at it now): then the smallest colour free at it;
        // on a mirror-exact cloth it takes c all the same, and the two are solved together (VbdGraph::paired).
        ++tag;
        mark_neighbours(t);
        const bool coupled = c < stamp.size() && stamp[c] == tag;
        if (coupled && g.mirror_exact) pair_of[i] = t;
        give(t, coupled && !g.mirror_exact ? smallest_free() : c);
    }
    return finish_colouring(g, colour, colours, pair_of);
}

namespace {

VbdGraph finish_colouring(VbdGraph& g, const std::vector<std::uint32_t>& colour, std::uint32_t colours,
                          const std::vector<std::uint32_t>& pair_of) {
    const std::size_t n = g.particle_count;
    g.colour_offsets.assign(colours + 1, 0);
    for (std::uint32_t c : colour) ++g.colour_offsets[c + 1];
    std::partial_sum(g.colour_offsets.begin(), g.colour_offsets.end(), g.colour_offsets.begin());
    g.colour_vertex.resize(n);
    g.paired.assign(n, 0);
    std::vector<std::uint32_t> fill(g.colour_offsets.begin(), g.colour_offsets.end() - 1);
    // Coupled mirror pairs open their colour (so a pair never straddles a SIMD slice: slices and chunks start at
    // the colour's start and hold an even number of vertices), then the rest in index order.
    const bool pairs = !pair_of.empty();
    std::vector<std::uint8_t> placed(pairs ? n : 0, 0);
    if (pairs)
        for (std::uint32_t i = 0; i < n; ++i) {
            const std::uint32_t t = pair_of[i];
            if (t == UINT32_MAX) continue;
            g.paired[fill[colour[i]]] = 1;
            g.colour_vertex[fill[colour[i]]++] = i;
            g.colour_vertex[fill[colour[i]]++] = t;
            placed[i] = placed[t] = 1;
        }
    for (std::uint32_t i = 0; i < n; ++i)
        if (!pairs || !placed[i]) g.colour_vertex[fill[colour[i]]++] = i;
    return std::move(g);
}

} // namespace

float contact_project(std::span<const Collider> colliders, const float p0[3], float p[3], float normal[3],
                      const Collider** held) noexcept {
    float mu = -1.0f;
    for (const Collider& c : colliders) {
        if (!is_inside(c, {p[0], p[1], p[2]})) continue;
        if (held != nullptr) *held = &c;
        // Started inside, or a plane (its tangent plane at the entry point is the plane itself, so the search for
        // the entry point below would end where projecting does): the nearest surface point.
        if (c.kind == ColliderKind::plane || is_inside(c, {p0[0], p0[1], p0[2]})) {
            const Contact ct = project_point(c, {p[0], p[1], p[2]});
            for (int k = 0; k < 3; ++k) {
                p[k] = ct.point[k];
                normal[k] = ct.normal[k];
            }
            mu = c.friction;
            continue;
        }
        const Contact ct = segment_entry(c, {p0[0], p0[1], p0[2]}, {p[0], p[1], p[2]});
        // Onto the tangent plane through the entry point.
        const float depth = (p[0] - ct.point[0]) * ct.normal[0] + (p[1] - ct.point[1]) * ct.normal[1] +
                            (p[2] - ct.point[2]) * ct.normal[2];
        if (depth < 0.0f)
            for (int k = 0; k < 3; ++k) p[k] -= depth * ct.normal[k];
        for (int k = 0; k < 3; ++k) normal[k] = ct.normal[k];
        mu = c.friction;
        if (is_inside(c, {p[0], p[1], p[2]})) { // a curved surface: the tangent plane can still be inside
            const Contact out = project_point(c, {p[0], p[1], p[2]});
            for (int k = 0; k < 3; ++k) p[k] = out.point[k];
        }
    }
    return mu;
}

bool solve_sym3(const float hess[6], const float r[3], float out[3]) noexcept {
    const float hxx = hess[0], hyy = hess[1], hzz = hess[2], hxy = hess[3], hxz = hess[4], hyz = hess[5];
    const float c00 = hyy * hzz - hyz * hyz, c01 = hxz * hyz - hxy * hzz, c02 = hxy * hyz - hxz * hyy;
    const float c11 = hxx * hzz - hxz * hxz, c12 = hxy * hxz - hxx * hyz, c22 = hxx * hyy - hxy * hxy;
    const float det = hxx * c00 + hxy * c01 + hxz * c02;
    if (!(det > 0.0f) || !std::isfinite(det)) return false;
    out[0] = (c00 * r[0] + c01 * r[1] + c02 * r[2]) / det;
    out[1] = (c01 * r[0] + c11 * r[1] + c12 * r[2]) / det;
    out[2] = (c02 * r[0] + c12 * r[1] + c22 * r[2]) / det;
    return true;
}

bool triangle_terms_step(const TriangleTerms& terms, std::uint32_t i, const float* x, const float* y,
                         const float* z, const std::uint32_t* slot, const float* x0, const float* y0,
                         const float* z0, float eps, const float x_now[3], float p[3],
                         float hess[6], bool exact) noexcept {
    // The model's gradient at x_now: H (x_now - p).
    const float dx = x_now[0] - p[0], dy = x_now[1] - p[1], dz = x_now[2] - p[2];
    float g[3] = {hess[0] * dx + hess[3] * dy + hess[4] * dz, hess[3] * dx + hess[1] * dy + hess[5] * dz,
                  hess[4] * dx + hess[5] * dy + hess[2] * dz};
    float ht[6] = {hess[0], hess[1], hess[2], hess[3], hess[4], hess[5]};
    // Exact (a mirror-exact cloth): friction summed apart from the normal terms, so that on the mirror plane each
    // term is added next to its mirror image's (the triangles come in mirror order) and the pair cancels exactly.
    float gf[3] = {0.0f, 0.0f, 0.0f}, hf6[6] = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
    float* gfric = exact ? gf : g;
    float* hfric = exact ? hf6 : ht;
    bool active = false;
    for (std::uint32_t k = terms.vertex_tri_offsets[i]; k < terms.vertex_tri_offsets[i + 1]; ++k) {
        const std::uint32_t t = terms.vertex_tris[k];
        if (!terms.tri_on[t]) continue;
        const float* e = terms.term + std::size_t(t) * triangle_term_floats;
        const std::uint32_t* v = terms.triangles + 3 * std::size_t(t);
        const float kc = e[3], mu = e[4];
        const Collider& col = terms.grown[terms.tri_on[t] - 1u];
        // The contact point q with vertex i at x_now, and its move over the step, q - q^n; the weight of
        // vertex i.
        float q[3] = {0.0f, 0.0f, 0.0f}, u[3] = {0.0f, 0.0f, 0.0f}, bi = 0.0f;
        for (int j = 0; j < 3; ++j) {
            const std::uint32_t vj = v[j];
            const std::size_t s = slot ? slot[vj] : vj;
            const float pj[3] = {vj == i ? x_now[0] : x[s], vj == i ? x_now[1] : y[s],
                                 vj == i ? x_now[2] : z[s]};
            if (vj == i) bi = e[j];
            q[0] += e[j] * pj[0];
            q[1] += e[j] * pj[1];
            q[2] += e[j] * pj[2];
            u[0] += e[j] * (pj[0] - x0[vj]);
            u[1] += e[j] * (pj[1] - y0[vj]);
            u[2] += e[j] * (pj[2] - z0[vj]);
        }
        // phi(q) and its normal: q farther than the reach from the inflated surface has no contact.
        Contact proj;
        float* kept = terms.plane && col.kind == ColliderKind::ellipsoid ? terms.plane + triangle_plane_floats * t
                                                                          : nullptr;
        bool reuse = false;
        if (kept) { // within the reuse radius of the kept plane's contact point (NaN: none kept)
            const float a_min = std::min({col.size[0], col.size[1], col.size[2]});
            const float r = triangle_plane_reuse * a_min * a_min / std::max({col.size[0], col.size[1], col.size[2]});
            const float mx = q[0] - kept[6], my = q[1] - kept[7], mz = q[2] - kept[8];
            reuse = mx * mx + my * my + mz * mz < r * r;
        }
        if (reuse) {
            proj.point = {kept[0], kept[1], kept[2]};
            proj.normal = {kept[3], kept[4], kept[5]};
            proj.inside = (kept[0] - q[0]) * kept[3] + (kept[1] - q[1]) * kept[4] + (kept[2] - q[2]) * kept[5] > 0.0f;
        } else {
            proj = project_point(col, {q[0], q[1], q[2]}, terms.warm ? terms.warm + t : nullptr);
            if (kept) {
                for (int c = 0; c < 3; ++c) {
                    kept[c] = proj.point[c];
                    kept[3 + c] = proj.normal[c];
                    kept[6 + c] = proj.inside ? q[c] : std::numeric_limits<float>::quiet_NaN();
                }
            }
        }
        if (!proj.inside) continue;
        const float nx = proj.normal[0], ny = proj.normal[1], nz = proj.normal[2];
        const float a = terms.reach - ((proj.point[0] - q[0]) * nx + (proj.point[1] - q[1]) * ny +
                                       (proj.point[2] - q[2]) * nz);
        const float a_free = a - bi * (nx * dx + ny * dy + nz * dz);
        if (!(a_free < 0.0f) || !(bi > 0.0f)) continue;
        active = true;
        const float gs = kc * a * bi, hs = kc * bi * bi;
        if (exact) add_isotropic_outer<true>(0.0f, hs, nx, ny, nz, ht[0], ht[1], ht[2], ht[3], ht[4], ht[5]);
        else add_isotropic_outer(0.0f, hs, nx, ny, nz, ht[0], ht[1], ht[2], ht[3], ht[4], ht[5]);
        g[0] += gs * nx;
        g[1] += gs * ny;
        g[2] += gs * nz;
        // Friction on the contact point (vertex friction's smoothed Coulomb model, vbd_batch.hpp): the normal
        // force lambda = k max(0, -a) against the tangential move u_T of the step, mu lambda u_T / max(|u_T|,
        // eps), shared by b_i; its Hessian b_i^2 mu lambda / max(|u_T|, eps) (I - n n^T).
        const float lambda = kc * std::max(-a, 0.0f);
        if (!(mu > 0.0f) || !(lambda > 0.0f)) continue;
        const float un = u[0] * nx + u[1] * ny + u[2] * nz;
        const float ut[3] = {u[0] - un * nx, u[1] - un * ny, u[2] - un * nz};
        const float len = std::sqrt(ut[0] * ut[0] + ut[1] * ut[1] + ut[2] * ut[2]);
        const float f = mu * lambda / std::max(len, eps);
        gfric[0] += bi * f * ut[0];
        gfric[1] += bi * f * ut[1];
        gfric[2] += bi * f * ut[2];
        const float hf = bi * bi * f;
        float* H = hfric;
        if (exact) add_isotropic_outer<true>(hf, -hf, nx, ny, nz, H[0], H[1], H[2], H[3], H[4], H[5]);
        else add_isotropic_outer(hf, -hf, nx, ny, nz, H[0], H[1], H[2], H[3], H[4], H[5]);
    }
    if (!active) return false;
    if (exact) {
        for (int c = 0; c < 3; ++c) g[c] += gf[c];
        for (int c = 0; c < 6; ++c) ht[c] += hf6[c];
    }
    float step[3];
    if (!solve_sym3(ht, g, step)) return false;
    for (int c = 0; c < 3; ++c) {
        if (!std::isfinite(step[c])) return false;
    }
    for (int c = 0; c < 3; ++c) {
        p[c] = x_now[c] - step[c];
        hess[c] = ht[c];
        hess[3 + c] = ht[3 + c];
    }
    return true;
}

bool contact_step(const float hess[6], const float x[3], const float free_step[3], float p[3],
                  const float normal[3]) noexcept {
    const float nx = normal[0], ny = normal[1], nz = normal[2];
    const float c = nx * p[0] + ny * p[1] + nz * p[2];
    const float gap = c - (nx * free_step[0] + ny * free_step[1] + nz * free_step[2]);
    if (!(gap > 0.0f)) return false;
    // w = H^-1 n (H symmetric positive definite).
    float w[3];
    if (!solve_sym3(hess, normal, w)) return false;
    const float wx = w[0], wy = w[1], wz = w[2];
    const float nw = nx * wx + ny * wy + nz * wz;
    if (!(nw > 0.0f) || !std::isfinite(nw)) return false;
    const float lambda = gap / nw;
    float sx = free_step[0] + lambda * wx - x[0], sy = free_step[1] + lambda * wy - x[1],
          sz = free_step[2] + lambda * wz - x[2];
    // A trust region: the constrained step no longer than contact_step_reach times the free step plus the gap (a
    // stiff spring along the normal sends H^-1 n sideways without bound).
    const float fx = free_step[0] - x[0], fy = free_step[1] - x[1], fz = free_step[2] - x[2];
    const float reach = contact_step_reach * (std::sqrt(fx * fx + fy * fy + fz * fz) + gap);
    const float len = std::sqrt(sx * sx + sy * sy + sz * sz);
    if (!std::isfinite(len)) return false;
    if (len > reach) {
        const float scale = reach / len;
        sx *= scale;
        sy *= scale;
        sz *= scale;
    }
    p[0] = x[0] + sx;
    p[1] = x[1] + sy;
    p[2] = x[2] + sz;
    return true;
}

namespace {
constexpr std::size_t vbd_chunk = 256; ///< vertices per parallel chunk of a colour (fixed: determinism)
/// Particles under which the sweeps run serially (the multilevel guess's small levels). Measured (2-core AVX2 machine,
/// drape_implicit throughput, 2 threads, N = 100 step at 25 iterations): 4096 -> 1024 31.5-32.8 -> 27.3-27.6 ms (its
/// 50 x 50 level went parallel); with 64-cell chunks (vbd_grid.cpp) 1024 -> 512 27.7-28.2 -> 25.6-25.9 ms (its 25 x 25
/// level too); 128 the same as 512; N = 316 unchanged by any of them.
constexpr std::size_t serial_below = 512;
/// The same for a cloth whose sweeps run on the grid layout. 2026-11-30 (2-core AVX-512 Intel machine, the fused
/// sweeps: a batch costs less, so a parallel loop's start-up counts more; drape_implicit realtime --n 100,316
/// --threads 2 --iterations 10 --strain-limit 0.095, real-time factor, runs alternated): 512 -> 4096 N = 100
/// 7.04 / 7.61 / 7.73 -> 8.19 / 8.46 (its 50 x 50 level serial again), N = 316 0.98 / 0.98 / 0.99 -> 0.95 / 0.99;
/// 8192 (N = 316's 79 x 79 level serial too) 8.36 / 8.38 and 0.93 / 0.96. Meshes (slices) keep 512: not measured.
constexpr std::size_t serial_below_grid = 4096;

/// One coordinate of the Chebyshev pass over [begin, end): x holds the sweeps' iterate xbar^(k), prev holds x^(k-2)
/// and receives x^(k) = w (xbar^(k) - x^(k-2)) + x^(k-2) (pinned points, inverse mass 0, keep xbar), which x receives
/// too. The first pass (first) extrapolates nothing. Branch-free over plain arrays, so it vectorises; the caller
/// swaps the roles of the x^(k-1) and x^(k-2) arrays afterwards instead of copying them.
void chebyshev_pass(float* __restrict x, float* __restrict prev, const float* __restrict inv_mass, std::size_t begin,
                    std::size_t end, float w, bool first) {
    if (first) {
        std::copy(x + begin, x + end, prev + begin);
        return;
    }
    for (std::size_t i = begin; i < end; ++i) {
        const float p = prev[i], xbar = x[i];
        const float extrapolated = w * (xbar - p) + p;
        const float v = inv_mass[i] != 0.0f ? extrapolated : xbar;
        x[i] = v;
        prev[i] = v;
    }
}
}

Solver::Solver() = default;
Solver::~Solver() = default;
Solver::Solver(Solver&&) noexcept = default;
Solver& Solver::operator=(Solver&&) noexcept = default;

void Solver::refresh_materials(const Cloth& cloth) {
    vbd::refresh_materials(graph_, cloth);
    if (grid_) grid_->refresh(graph_);
    VbdSlices& sl = *slices_;
    for (std::size_t e = 0; e < sl.spring_edge.size(); ++e) {
        if (sl.spring_edge[e] == UINT32_MAX) continue;
        const Edge& edge = cloth.edges[sl.spring_edge[e]];
        const SpringMaterial& m = cloth.material[static_cast<std::size_t>(edge.kind)];
        sl.spring_k[e] = m.stiffness * edge.scale;
        sl.spring_kd[e] = m.damping * edge.scale;
    }
}

void Solver::set_spring_rest(std::span<const float> edge_rest) {
    for (std::size_t e = 0; e < graph_.spring_edge.size(); ++e) graph_.spring_rest[e] = edge_rest[graph_.spring_edge[e]];
    if (grid_) grid_->refresh_rest(graph_);
    if (!slices_) return;
    VbdSlices& sl = *slices_;
    for (std::size_t k = 0; k < sl.spring_edge.size(); ++k)
        if (sl.spring_edge[k] != UINT32_MAX) sl.spring_rest[k] = edge_rest[sl.spring_edge[k]];
}

void Solver::cook(const Cloth& cloth, std::span<const std::uint32_t> twin) {
    graph_ = vbd::cook(cloth, twin);
    static_assert(vbd_chunk % simd::width == 0, "a chunk is whole slices");
    constexpr std::size_t W = simd::width;
    const VbdGraph& g = graph_;
    slices_ = std::make_unique<VbdSlices>();
    VbdSlices& sl = *slices_;
    // Slices of W vertices of each colour, in the colour's order; springs and bending rows slot-major.
    std::vector<std::uint32_t> vertex, spring_neighbour, spring_edge, bend_neighbour;
    std::vector<float> spring_k, spring_kd, spring_rest, bend_q;
    for (std::size_t c = 0; c < g.colour_count(); ++c) {
        sl.colour_slices.push_back(static_cast<std::uint32_t>(sl.lanes.size()));
        for (std::uint32_t first = g.colour_offsets[c]; first < g.colour_offsets[c + 1]; first += W) {
            const std::uint32_t lanes = std::min<std::uint32_t>(W, g.colour_offsets[c + 1] - first);
            sl.lanes.push_back(lanes);
            std::uint32_t springs = 0, bends = 0;
            for (std::uint32_t k = 0; k < W; ++k) {
                const std::uint32_t v = g.colour_vertex[first + (k < lanes ? k : 0)];
                vertex.push_back(v);
                springs = std::max(springs, g.spring_offsets[v + 1] - g.spring_offsets[v]);
                if (!g.bend_offsets.empty()) bends = std::max(bends, g.bend_offsets[v + 1] - g.bend_offsets[v]);
            }
            sl.spring_begin.push_back(static_cast<std::uint32_t>(spring_neighbour.size()));
            sl.spring_slots.push_back(springs);
            for (std::uint32_t s = 0; s < springs; ++s)
                for (std::uint32_t k = 0; k < W; ++k) {
                    const std::uint32_t v = vertex[vertex.size() - W + k];
                    const std::uint32_t e = g.spring_offsets[v] + s;
                    const bool real = k < lanes && e < g.spring_offsets[v + 1];
                    spring_neighbour.push_back(real ? g.spring_neighbour[e] : v);
                    spring_edge.push_back(real ? g.spring_edge[e] : UINT32_MAX);
                    spring_k.push_back(real ? g.spring_k[e] : 0.0f);
                    spring_kd.push_back(real ? g.spring_kd[e] : 0.0f);
                    spring_rest.push_back(real ? g.spring_rest[e] : 0.0f);
                }
            sl.bend_begin.push_back(static_cast<std::uint32_t>(bend_neighbour.size()));
            sl.bend_slots.push_back(bends);
            for (std::uint32_t s = 0; s < bends; ++s)
                for (std::uint32_t k = 0; k < W; ++k) {
                    const std::uint32_t v = vertex[vertex.size() - W + k];
                    const std::uint32_t e = g.bend_offsets[v] + s;
                    const bool real = k < lanes && e < g.bend_offsets[v + 1];
                    bend_neighbour.push_back(real ? g.bend_neighbour[e] : v);
                    bend_q.push_back(real ? g.bend_q[e] : 0.0f);
                }
        }
    }
    sl.colour_slices.push_back(static_cast<std::uint32_t>(sl.lanes.size()));
    auto fill_u = [](AlignedArray<std::uint32_t>& out, const std::vector<std::uint32_t>& in) {
        out.reset(in.size());
        std::copy(in.begin(), in.end(), out.data());
    };
    auto fill_f = [](AlignedArray<float>& out, const std::vector<float>& in) {
        out.reset(in.size());
        std::copy(in.begin(), in.end(), out.data());
    };
    fill_u(sl.vertex, vertex);
    fill_u(sl.spring_neighbour, spring_neighbour);
    fill_u(sl.spring_edge, spring_edge);
    fill_f(sl.spring_k, spring_k);
    fill_f(sl.spring_kd, spring_kd);
    fill_f(sl.spring_rest, spring_rest);
    fill_u(sl.bend_neighbour, bend_neighbour);
    fill_f(sl.bend_q, bend_q);
    const std::size_t n = cloth.particle_count;
    grid_ = cloth.grid ? GridLayout::cook(graph_, cloth.grid->rows, cloth.grid->columns) : nullptr;
    const std::size_t state = std::max(n, grid_ ? grid_->cells() : 0);
    for (std::vector<float>* a : {&cheb1_x_, &cheb1_y_, &cheb1_z_, &cheb2_x_, &cheb2_y_, &cheb2_z_}) a->assign(state, 0.0f);
    for (std::vector<float>* a : {&pred_x_, &pred_y_, &pred_z_, &jac_x_, &jac_y_, &jac_z_, &contact_nx_, &contact_ny_, &contact_nz_})
        a->assign(n, 0.0f);
    for (AlignedArray<float>* a : {&fr_nx_, &fr_ny_, &fr_nz_, &fr_k_}) a->reset(state);
    colour_chunk_base_.assign(graph_.colour_count() + 1, 0);
    for (std::size_t c = 0; c < graph_.colour_count(); ++c) {
        const std::size_t size = graph_.colour_offsets[c + 1] - graph_.colour_offsets[c];
        colour_chunk_base_[c + 1] =
            colour_chunk_base_[c] + static_cast<std::uint32_t>((size + vbd_chunk - 1) / vbd_chunk);
    }
    const std::size_t jacobi_chunks = (n + vbd_chunk - 1) / vbd_chunk;
    const std::size_t grid_chunks = grid_ ? grid_->colour_count() * grid_->chunks_per_colour() : 0;
    chunk_residual_.assign(std::max({std::size_t(colour_chunk_base_.back()), jacobi_chunks, grid_chunks}), 0.0);
}

template <bool Parallel>
ImplicitStats Solver::run(const LevelState& st, const ImplicitParams& ip, float h, float air_drag) {
    const std::size_t n = graph_.particle_count;
    // A small cloth (the multilevel solver's coarse levels) runs serially: a parallel loop per colour costs a few
    // microseconds to start, more than such a colour's work, and the serial twin gives the same bits.
    if constexpr (Parallel)
        if (n < (grid_sweeps() ? serial_below_grid : serial_below)) return run<false>(st, ip, h, air_drag);
    const float inv_h = 1.0f / h;
    const float* inv_mass = st.inv_mass;
    float *x = st.x, *y = st.y, *z = st.z;
    SweepArgs args{st.x0,    st.y0,   st.z0,         pred_x_.data(),   pred_y_.data(), pred_z_.data(), x, y, z,
                   inv_mass, &graph_, inv_h * inv_h, air_drag * inv_h, inv_h};
    const bool colliders = !st.colliders.empty();
    if (colliders) {
        args.fr_nx = fr_nx_.data();
        args.fr_ny = fr_ny_.data();
        args.fr_nz = fr_nz_.data();
        args.fr_k = fr_k_.data();
        args.fr_eps = friction_slip_speed * h;
    }
    const bool jacobi = ip.method == ImplicitMethod::jacobi;
    // A grid cloth's Gauss-Seidel sweeps run on its packed colour sub-grids (vbd_grid.hpp); the Chebyshev pass below
    // is element by element, so it runs on whichever arrays hold the iterate (count of them, mass their masses).
    const bool grid = !jacobi && grid_sweeps();
    // The triangle terms' warm starts and kept tangent planes pass from one corner's step to the next: the Jacobi
    // sweep steps all corners at once, so it projects every triangle cold.
    TriangleTerms cold_terms;
    const TriangleTerms* triangle_terms = st.triangle_terms;
    if (jacobi && triangle_terms && (triangle_terms->warm || triangle_terms->plane)) {
        cold_terms = *triangle_terms;
        cold_terms.warm = nullptr;
        cold_terms.plane = nullptr;
        triangle_terms = &cold_terms;
    }
    // Contact, vertex by vertex right after its local step (its neighbours then never see it inside a collider):
    // out of every collider from the side the step came from. The contact's normal and its friction bound become the
    // vertex's friction in its next local steps (SweepArgs::fr_k, written at `slot`, the vertex's place in the
    // iterate): mu times the normal force, m/h^2 times the distance the contact holds the point from its inertial
    // prediction (an impulse that stops the approach within the step).
    const float inv_h2 = inv_h * inv_h;
    auto friction_from = [&](std::size_t i, std::size_t slot, const float p[3], const float normal[3], float mu) {
        const float held = (p[0] - pred_x_[i]) * normal[0] + (p[1] - pred_y_[i]) * normal[1] +
                           (p[2] - pred_z_[i]) * normal[2];
        fr_nx_[slot] = normal[0];
        fr_ny_[slot] = normal[1];
        fr_nz_[slot] = normal[2];
        fr_k_[slot] = mu > 0.0f ? mu * std::max(held, 0.0f) * inv_h2 / inv_mass[i] : 0.0f;
        return mu > 0.0f ? mu * std::max(held, 0.0f) : 0.0f;
    };
    // The friction of the first sweep: the contacts of the inertial prediction (the grid's cells outside the cloth
    // keep zero). A guess that is the inertial prediction (LevelState::coulomb_guess) also loses the Coulomb share of its
    // tangential displacement, vertex by vertex: exact for a cloth sliding as a whole, which the sweeps (slow to move
    // a stiff cloth as a whole: its springs hold each vertex to its neighbours) then only keep.
    if (colliders)
        for_each_index<Parallel>((n + block_particles - 1) / block_particles, [&](std::size_t blk) {
            for (std::size_t i = blk * block_particles, end = std::min(n, (blk + 1) * block_particles); i < end; ++i) {
                const std::size_t slot = grid ? grid_->cell_of(i) : i;
                float p[3] = {pred_x_[i], pred_y_[i], pred_z_[i]}, normal[3] = {0.0f, 0.0f, 0.0f};
                const float p0[3] = {st.x0[i], st.y0[i], st.z0[i]};
                const float mu = inv_mass[i] != 0.0f ? contact_project(st.colliders, p0, p, normal) : -1.0f;
                const float limit = friction_from(i, slot, p, normal, std::max(mu, 0.0f));
                if (!st.coulomb_guess || limit == 0.0f) continue;
                // The guess's own tangential displacement (it stays where contact left it along the normal).
                const float dx = st.x[i] - p0[0], dy = st.y[i] - p0[1], dz = st.z[i] - p0[2];
                const float dn = dx * normal[0] + dy * normal[1] + dz * normal[2];
                const float tx = dx - dn * normal[0], ty = dy - dn * normal[1], tz = dz - dn * normal[2];
                const float t = std::sqrt(tx * tx + ty * ty + tz * tz);
                const float lost = t > limit ? limit / t : 1.0f; // the share of it friction takes
                st.x[i] -= lost * tx;
                st.y[i] -= lost * ty;
                st.z[i] -= lost * tz;
            }
        });
    std::size_t count = n;
    const float* mass = inv_mass;
    if (grid) {
        grid_->pack<Parallel>(st, pred_x_.data(), pred_y_.data(), pred_z_.data());
        args = grid_->packed_args(args);
        grid_->cook_damping<Parallel>(args);
        x = grid_->x();
        y = grid_->y();
        z = grid_->z();
        count = grid_->cells();
        mass = grid_->inv_mass();
    }
    // Chebyshev's extrapolation and contact disagree (it throws points a collider holds back into the air: a cloth
    // resting on the ground bounced 3 cm, measured), so with colliders the sweeps run plain.
    const bool planes = st.plane_c != nullptr;
    const bool contact = colliders || planes;
    const bool constrained_steps = st.contact_steps && !planes; // LevelState::contact_steps
    // With few sweeps its extrapolation is left uncorrected (chebyshev_min_iterations: plain sweeps) or cycles
    // (chebyshev_full_iterations: a smaller rho).
    const float rho = chebyshev_rho_for(ip);
    const bool chebyshev = rho > 0.0f && st.colliders.empty() && !planes;
    const float rho2 = rho * rho;
    const std::size_t blocks = (count + block_particles - 1) / block_particles;
    float omega = 1.0f;
    // x^(k-1) and x^(k-2) of the Chebyshev pass: two sets of arrays whose roles swap after each pass.
    float *c1x = cheb1_x_.data(), *c1y = cheb1_y_.data(), *c1z = cheb1_z_.data();
    float *c2x = cheb2_x_.data(), *c2y = cheb2_y_.data(), *c2z = cheb2_z_.data();
    if (chebyshev) {
        std::copy_n(x, count, c1x);
        std::copy_n(y, count, c1y);
        std::copy_n(z, count, c1z);
    }
    const std::uint32_t* cell_of = grid ? grid_->cell_of_data() : nullptr;
    auto keep_out = [&](std::size_t i, std::size_t slot, float p[3], const float* hess) {
        // The triangles' contact terms first: the step they give is then the free step below.
        float terms_hess[6];
        if (triangle_terms && triangle_terms->vertex_on[i]) {
            const float x_now[3] = {x[slot], y[slot], z[slot]};
            std::copy_n(hess, 6, terms_hess);
            if (triangle_terms_step(*triangle_terms, static_cast<std::uint32_t>(i), x, y, z, cell_of,
                                    st.x0, st.y0, st.z0, args.fr_eps, x_now, p, terms_hess, graph_.mirror_exact))
                hess = terms_hess;
        }
        if (planes) { // self-contact: not closer to the partner than the plane the contact left the vertex on
            const float nx = st.plane_nx[i], ny = st.plane_ny[i], nz = st.plane_nz[i];
            const float gap = st.plane_c[i] - (nx * p[0] + ny * p[1] + nz * p[2]);
            if (gap > 0.0f) {
                p[0] += gap * nx;
                p[1] += gap * ny;
                p[2] += gap * nz;
            }
        }
        if (!colliders) return;
        const float p0[3] = {st.x0[i], st.y0[i], st.z0[i]};
        float normal[3] = {0.0f, 0.0f, 0.0f};
        const float free_step[3] = {p[0], p[1], p[2]};
        const Collider* held = nullptr;
        float mu = contact_project(st.colliders, p0, p, normal, &held);
        // Only against a solid: on a plane the projection is the constrained step's normal part already, and the
        // tangential move H^-1 n adds spread a crumpled cloth landing on the ground (a tank top's single-level
        // steps reached strain 1.29 and were stopped).
        if (mu >= 0.0f && held->kind != ColliderKind::plane) {
            // The step ended inside a collider: take the local quadratic model's minimum on the contact's tangent
            // plane instead of the free step's projection (contact_step), then keep out of every collider again.
            const float x_now[3] = {x[slot], y[slot], z[slot]};
            if (constrained_steps && contact_step(hess, x_now, free_step, p, normal)) {
                float again[3] = {0.0f, 0.0f, 0.0f};
                const float mu2 = contact_project(st.colliders, p0, p, again);
                if (mu2 >= 0.0f) {
                    mu = mu2;
                    std::copy_n(again, 3, normal);
                }
            }
        }
        friction_from(i, slot, p, normal, std::max(mu, 0.0f));
        contact_nx_[i] = normal[0];
        contact_ny_[i] = normal[1];
        contact_nz_[i] = normal[2];
    };
    ImplicitStats stats;
    for (std::uint32_t it = 0; it < ip.iterations; ++it) {
        std::size_t chunks_used = 0;
        if (grid) {
            const std::size_t chunks = grid_->chunks_per_colour();
            for (std::size_t c = 0; c < grid_->colour_count(); ++c)
                for_each_index<Parallel>(chunks, [&](std::size_t ch) {
                    chunk_residual_[c * chunks + ch] = grid_->solve_chunk(args, c, ch, contact, keep_out);
                });
            chunks_used = grid_->colour_count() * chunks;
        } else if (!jacobi) {
            for (std::size_t c = 0; c < graph_.colour_count(); ++c) {
                const std::uint32_t first = graph_.colour_offsets[c], last = graph_.colour_offsets[c + 1];
                const std::uint32_t base = colour_chunk_base_[c];
                for_each_index<Parallel>(colour_chunk_base_[c + 1] - base, [&](std::size_t ch) {
                    double r = 0.0;
                    const std::uint32_t lo = first + static_cast<std::uint32_t>(ch * vbd_chunk);
                    const std::uint32_t hi = std::min<std::uint32_t>(last, lo + static_cast<std::uint32_t>(vbd_chunk));
                    if (simd_) { // the chunk's slices: W vertices at once, then each live movable lane in order
                        constexpr std::size_t W = simd::width;
                        const VbdSlices& sl = *slices_;
                        const std::size_t s0 = sl.colour_slices[c] + ch * (vbd_chunk / W);
                        const std::size_t s1 = s0 + (hi - lo + W - 1) / W;
                        alignas(64) float ox[W], oy[W], oz[W], g2[W], hs[6 * W];
                        for (std::size_t slice = s0; slice < s1; ++slice) {
                            if (graph_.mirror_exact)
                                solve_batch<true>(args, sl, slice, ox, oy, oz, g2, contact ? hs : nullptr);
                            else
                                solve_batch<false>(args, sl, slice, ox, oy, oz, g2, contact ? hs : nullptr);
                            for (std::uint32_t lane = 0; lane < sl.lanes[slice]; ++lane) {
                                const std::uint32_t i = sl.vertex[slice * W + lane];
                                if (inv_mass[i] == 0.0f) continue;
                                r += g2[lane];
                                float out[3] = {ox[lane], oy[lane], oz[lane]};
                                const float hess[6] = {hs[lane],         hs[W + lane],     hs[2 * W + lane],
                                                       hs[3 * W + lane], hs[4 * W + lane], hs[5 * W + lane]};
                                if (contact) keep_out(i, i, out, hess);
                                x[i] = out[0];
                                y[i] = out[1];
                                z[i] = out[2];
                            }
                        }
                        chunk_residual_[base + ch] = r;
                        return;
                    }
                    // The scalar reference: vertex by vertex, except a coupled mirror pair (VbdGraph::paired), whose
                    // two steps are both taken from the same positions before either is written, as the SIMD
                    // slice's lanes are.
                    const bool exact = graph_.mirror_exact;
                    for (std::uint32_t k = lo; k < hi; ++k) {
                        const std::uint32_t count = exact && graph_.paired[k] ? 2u : 1u;
                        float out[2][3], hess[2][6];
                        double g2[2] = {0.0, 0.0};
                        for (std::uint32_t m = 0; m < count; ++m) {
                            const std::uint32_t i = graph_.colour_vertex[k + m];
                            if (inv_mass[i] == 0.0f) continue;
                            g2[m] = exact ? solve_vertex<false, true>(args, i, out[m], hess[m])
                                          : solve_vertex(args, i, out[m], hess[m]);
                        }
                        for (std::uint32_t m = 0; m < count; ++m) {
                            const std::uint32_t i = graph_.colour_vertex[k + m];
                            if (inv_mass[i] == 0.0f) continue;
                            r += g2[m];
                            if (contact) keep_out(i, i, out[m], hess[m]);
                            x[i] = out[m][0];
                            y[i] = out[m][1];
                            z[i] = out[m][2];
                        }
                        k += count - 1;
                    }
                    chunk_residual_[base + ch] = r;
                });
            }
            chunks_used = colour_chunk_base_.back();
        } else {
            const std::size_t chunks = (n + vbd_chunk - 1) / vbd_chunk;
            for_each_index<Parallel>(chunks, [&](std::size_t ch) {
                double r = 0.0;
                for (std::size_t i = ch * vbd_chunk, hi = std::min(n, (ch + 1) * vbd_chunk); i < hi; ++i) {
                    float out[3] = {x[i], y[i], z[i]}, hess[6];
                    if (inv_mass[i] != 0.0f) {
                        r += graph_.mirror_exact ? solve_vertex<false, true>(args, static_cast<std::uint32_t>(i), out, hess)
                                                 : solve_vertex(args, static_cast<std::uint32_t>(i), out, hess);
                        if (contact) keep_out(i, i, out, hess);
                    }
                    jac_x_[i] = out[0];
                    jac_y_[i] = out[1];
                    jac_z_[i] = out[2];
                }
                chunk_residual_[ch] = r;
            });
            std::copy_n(jac_x_.data(), n, x);
            std::copy_n(jac_y_.data(), n, y);
            std::copy_n(jac_z_.data(), n, z);
            chunks_used = chunks;
        }
        double r2 = 0.0; // in chunk order: the same bits for any thread count
        for (std::size_t ch = 0; ch < chunks_used; ++ch) r2 += chunk_residual_[ch];
        const double r = std::sqrt(r2);
        if (it == 0) stats.first_residual = r;
        stats.last_residual = r;
        stats.iterations = it + 1;

        if (chebyshev) {
            // x^(k) = omega (xbar^(k) - x^(k-2)) + x^(k-2); omega_1 = 1, omega_2 = 2 / (2 - rho^2),
            // omega_k = 4 / (4 - rho^2 omega_{k-1}).
            omega = it == 0 ? 1.0f : it == 1 ? 2.0f / (2.0f - rho2) : 4.0f / (4.0f - rho2 * omega);
            const float w = omega;
            const bool first = it == 0;
            for_each_index<Parallel>(blocks, [&](std::size_t blk) {
                const std::size_t begin = blk * block_particles, end = std::min(begin + block_particles, count);
                chebyshev_pass(x, c2x, mass, begin, end, w, first);
                chebyshev_pass(y, c2y, mass, begin, end, w, first);
                chebyshev_pass(z, c2z, mass, begin, end, w, first);
            });
            // The arrays just written hold x^(k), the others x^(k-1): they are the next pass's x^(k-1) and x^(k-2).
            std::swap(c1x, c2x);
            std::swap(c1y, c2y);
            std::swap(c1z, c2z);
        }
        if (ip.tolerance > 0.0f && r <= double(ip.tolerance) * stats.first_residual) break;
    }
    if (grid) grid_->unpack<Parallel>(st);
    stats.relative_residual = stats.first_residual > 0.0 ? stats.last_residual / stats.first_residual : 0.0;
    return stats;
}

template <bool Parallel>
void Solver::gradient(const Point& st, float h, float air_drag, float* gx, float* gy, float* gz) const {
    const std::size_t n = graph_.particle_count;
    const float inv_h = 1.0f / h;
    const SweepArgs args{st.x0,       st.y0,    st.z0,         pred_x_.data(),   pred_y_.data(), pred_z_.data(),
                         st.x,        st.y,     st.z,          st.inv_mass,      &graph_,        inv_h * inv_h,
                         air_drag * inv_h, inv_h};
    if (simd_) { // the slices (every vertex is in one), simd::width vertices at once: solve_vertex<true>'s bits
        constexpr std::size_t W = simd::width, slices_per_block = block_particles / W;
        const VbdSlices& sl = *slices_;
        const std::size_t slices = sl.lanes.size();
        for_each_index<Parallel>((slices + slices_per_block - 1) / slices_per_block, [&](std::size_t blk) {
            alignas(64) float ox[W], oy[W], oz[W];
            for (std::size_t slice = blk * slices_per_block, end = std::min(slices, (blk + 1) * slices_per_block);
                 slice < end; ++slice) {
                simd::fbatch bx, by, bz, b2;
                if (graph_.mirror_exact)
                    solve_lanes<true, true>(SliceSource(sl, graph_, slice), args, bx, by, bz, b2);
                else
                    solve_lanes<true, false>(SliceSource(sl, graph_, slice), args, bx, by, bz, b2);
                simd::store(ox, bx);
                simd::store(oy, by);
                simd::store(oz, bz);
                for (std::uint32_t lane = 0; lane < sl.lanes[slice]; ++lane) {
                    const std::uint32_t i = sl.vertex[slice * W + lane];
                    const bool movable = st.inv_mass[i] != 0.0f;
                    gx[i] = movable ? ox[lane] : 0.0f;
                    gy[i] = movable ? oy[lane] : 0.0f;
                    gz[i] = movable ? oz[lane] : 0.0f;
                }
            }
        });
        return;
    }
    for_each_index<Parallel>((n + block_particles - 1) / block_particles, [&](std::size_t blk) {
        for (std::size_t i = blk * block_particles, end = std::min(n, (blk + 1) * block_particles); i < end; ++i) {
            float g[3] = {0.0f, 0.0f, 0.0f};
            if (st.inv_mass[i] != 0.0f) {
                if (graph_.mirror_exact)
                    solve_vertex<true, true>(args, static_cast<std::uint32_t>(i), g);
                else
                    solve_vertex<true>(args, static_cast<std::uint32_t>(i), g);
            }
            gx[i] = g[0];
            gy[i] = g[1];
            gz[i] = g[2];
        }
    });
}

template void Solver::gradient<true>(const Point&, float, float, float*, float*, float*) const;
template void Solver::gradient<false>(const Point&, float, float, float*, float*, float*) const;
template ImplicitStats Solver::run<true>(const LevelState&, const ImplicitParams&, float, float);
template ImplicitStats Solver::run<false>(const LevelState&, const ImplicitParams&, float, float);

} // namespace drape::vbd
