// Cooking for vertex block descent: per-vertex springs (CSR), bending rows in float, and a greedy vertex colouring.
#include "vbd.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "for_each_index.hpp"

namespace drape::vbd {

void refresh_materials(VbdGraph& g, const Cloth& cloth) {
    for (std::size_t e = 0; e < g.spring_edge.size(); ++e) {
        const Edge& edge = cloth.edges[g.spring_edge[e]];
        const SpringMaterial& m = cloth.material[static_cast<std::size_t>(edge.kind)];
        g.spring_k[e] = m.stiffness * edge.scale;
        g.spring_kd[e] = m.damping * edge.scale;
    }
}

VbdGraph cook(const Cloth& cloth) {
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
        g.bend_q.resize(bend.value.size());
        g.bend_diag.assign(n, 0.0f);
        for (std::size_t i = 0; i < n; ++i) {
            double diag = 0.0;
            for (std::uint32_t e = bend.offsets[i]; e < bend.offsets[i + 1]; ++e) {
                g.bend_q[e] = static_cast<float>(bend.value[e]);
                diag -= bend.value[e];
            }
            g.bend_diag[i] = static_cast<float>(diag);
        }
        g.bend_beta = bend.damping;
    }

    // Greedy colouring in index order: each vertex takes the smallest colour none of its coupled neighbours
    // (springs or bending) has yet.
    std::vector<std::uint32_t> colour(n, UINT32_MAX);
    std::vector<std::uint32_t> stamp; // stamp[c] == i + 1: colour c is taken by a neighbour of i
    std::uint32_t colours = 0;
    for (std::uint32_t i = 0; i < n; ++i) {
        auto mark = [&](std::uint32_t j) {
            const std::uint32_t c = colour[j];
            if (c == UINT32_MAX) return;
            if (c >= stamp.size()) stamp.resize(c + 1, 0);
            stamp[c] = i + 1;
        };
        for (std::uint32_t e = g.spring_offsets[i]; e < g.spring_offsets[i + 1]; ++e) mark(g.spring_neighbour[e]);
        if (!bend.empty())
            for (std::uint32_t e = bend.offsets[i]; e < bend.offsets[i + 1]; ++e) mark(bend.neighbour[e]);
        std::uint32_t c = 0;
        while (c < stamp.size() && stamp[c] == i + 1) ++c;
        colour[i] = c;
        colours = std::max(colours, c + 1);
    }
    g.colour_offsets.assign(colours + 1, 0);
    for (std::uint32_t c : colour) ++g.colour_offsets[c + 1];
    std::partial_sum(g.colour_offsets.begin(), g.colour_offsets.end(), g.colour_offsets.begin());
    g.colour_vertex.resize(n);
    fill.assign(g.colour_offsets.begin(), g.colour_offsets.end() - 1);
    for (std::uint32_t i = 0; i < n; ++i) g.colour_vertex[fill[colour[i]]++] = i;
    return g;
}

namespace {
constexpr std::size_t vbd_chunk = 256; ///< vertices per parallel chunk of a colour (fixed: determinism)
}

void Solver::cook(const Cloth& cloth) {
    graph_ = vbd::cook(cloth);
    const std::size_t n = cloth.particle_count;
    for (std::vector<float>* a : {&pred_x_, &pred_y_, &pred_z_, &cheb1_x_, &cheb1_y_, &cheb1_z_, &cheb2_x_, &cheb2_y_,
                                  &cheb2_z_, &jac_x_, &jac_y_, &jac_z_})
        a->assign(n, 0.0f);
    colour_chunk_base_.assign(graph_.colour_count() + 1, 0);
    for (std::size_t c = 0; c < graph_.colour_count(); ++c) {
        const std::size_t size = graph_.colour_offsets[c + 1] - graph_.colour_offsets[c];
        colour_chunk_base_[c + 1] =
            colour_chunk_base_[c] + static_cast<std::uint32_t>((size + vbd_chunk - 1) / vbd_chunk);
    }
    const std::size_t jacobi_chunks = (n + vbd_chunk - 1) / vbd_chunk;
    chunk_residual_.assign(std::max<std::size_t>(colour_chunk_base_.back(), jacobi_chunks), 0.0);
}

template <bool Parallel>
ImplicitStats Solver::run(const LevelState& st, const ImplicitParams& ip, float h, float air_drag) {
    const std::size_t n = graph_.particle_count;
    const float inv_h = 1.0f / h;
    const float* inv_mass = st.inv_mass;
    float *x = st.x, *y = st.y, *z = st.z;
    const SweepArgs args{st.x0,         st.y0,         st.z0, pred_x_.data(), pred_y_.data(), pred_z_.data(), x, y, z,
                         inv_mass,      &graph_,       inv_h * inv_h, air_drag * inv_h, inv_h};
    const bool jacobi = ip.method == ImplicitMethod::jacobi;
    const bool chebyshev = ip.chebyshev_rho > 0.0f;
    const float rho2 = ip.chebyshev_rho * ip.chebyshev_rho;
    const std::size_t blocks = (n + block_particles - 1) / block_particles;
    float omega = 1.0f;
    if (chebyshev) {
        std::copy_n(x, n, cheb1_x_.data());
        std::copy_n(y, n, cheb1_y_.data());
        std::copy_n(z, n, cheb1_z_.data());
    }
    ImplicitStats stats;
    for (std::uint32_t it = 0; it < ip.iterations; ++it) {
        std::size_t chunks_used = 0;
        if (!jacobi) {
            for (std::size_t c = 0; c < graph_.colour_count(); ++c) {
                const std::uint32_t first = graph_.colour_offsets[c], last = graph_.colour_offsets[c + 1];
                const std::uint32_t base = colour_chunk_base_[c];
                for_each_index<Parallel>(colour_chunk_base_[c + 1] - base, [&](std::size_t ch) {
                    double r = 0.0;
                    const std::uint32_t lo = first + static_cast<std::uint32_t>(ch * vbd_chunk);
                    const std::uint32_t hi = std::min<std::uint32_t>(last, lo + static_cast<std::uint32_t>(vbd_chunk));
                    for (std::uint32_t k = lo; k < hi; ++k) {
                        const std::uint32_t i = graph_.colour_vertex[k];
                        if (inv_mass[i] == 0.0f) continue;
                        float out[3];
                        r += solve_vertex(args, i, out);
                        x[i] = out[0];
                        y[i] = out[1];
                        z[i] = out[2];
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
                    float out[3] = {x[i], y[i], z[i]};
                    if (inv_mass[i] != 0.0f) r += solve_vertex(args, static_cast<std::uint32_t>(i), out);
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
            for_each_index<Parallel>(blocks, [&](std::size_t blk) {
                const std::size_t begin = blk * block_particles, end = std::min(begin + block_particles, n);
                for (std::size_t i = begin; i < end; ++i) {
                    float px = x[i], py = y[i], pz = z[i];
                    if (it > 0 && inv_mass[i] != 0.0f) {
                        px = w * (px - cheb2_x_[i]) + cheb2_x_[i];
                        py = w * (py - cheb2_y_[i]) + cheb2_y_[i];
                        pz = w * (pz - cheb2_z_[i]) + cheb2_z_[i];
                        x[i] = px;
                        y[i] = py;
                        z[i] = pz;
                    }
                    cheb2_x_[i] = cheb1_x_[i];
                    cheb2_y_[i] = cheb1_y_[i];
                    cheb2_z_[i] = cheb1_z_[i];
                    cheb1_x_[i] = px;
                    cheb1_y_[i] = py;
                    cheb1_z_[i] = pz;
                }
            });
        }
        if (ip.tolerance > 0.0f && r <= double(ip.tolerance) * stats.first_residual) break;
    }
    stats.relative_residual = stats.first_residual > 0.0 ? stats.last_residual / stats.first_residual : 0.0;
    return stats;
}

template ImplicitStats Solver::run<true>(const LevelState&, const ImplicitParams&, float, float);
template ImplicitStats Solver::run<false>(const LevelState&, const ImplicitParams&, float, float);

} // namespace drape::vbd
