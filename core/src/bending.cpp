// Bending elements: validation, Q assembled per particle (CSR and SELL-C), and the double-precision reference of
// the energy, its gradient and its Hessian (bending.hpp, docs/fabric.md "Bending energy").
#include "drape/bending.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "drape/cloth.hpp"
#include "drape/errors.hpp"
#include "drape/mirror_symmetry.hpp"
#include "drape/simd.hpp"
#include "sell_layout.hpp"

namespace drape {

namespace {

void check_element(const BendElement& e, std::size_t index, std::size_t particle_count) {
    const std::string what = "bending element " + std::to_string(index);
    if (!(e.weight >= 0.0f) || !std::isfinite(e.weight))
        throw InvalidInput(what + " has weight " + std::to_string(e.weight) + " N/m (must be finite and >= 0)");
    double sum = 0.0, magnitude = 0.0;
    for (std::size_t k = 0; k < 4; ++k) {
        if (e.v[k] >= particle_count)
            throw InvalidInput(what + " names particle " + std::to_string(e.v[k]) + ", outside [0, " +
                               std::to_string(particle_count - 1) + "]");
        if (!std::isfinite(e.c[k]))
            throw InvalidInput(what + " has a non-finite coefficient " + std::to_string(e.c[k]));
        sum += e.c[k];
        magnitude += std::fabs(e.c[k]);
    }
    if (!(std::fabs(sum) <= 1e-5 * magnitude))
        throw InvalidInput(what + ": its coefficients sum to " + std::to_string(sum) +
                           " (must be 0: a translation of the cloth stores no bending energy)");
}

/// q_e at x, y, z, in double.
std::array<double, 3> element_q(const BendElement& e, std::span<const float> x, std::span<const float> y,
                                std::span<const float> z) {
    std::array<double, 3> q{0.0, 0.0, 0.0};
    for (std::size_t k = 0; k < 4; ++k) {
        const double c = e.c[k];
        q[0] += c * x[e.v[k]];
        q[1] += c * y[e.v[k]];
        q[2] += c * z[e.v[k]];
    }
    return q;
}

} // namespace

std::vector<BendTriplet> bending_hessian(std::span<const BendElement> elements, std::size_t particle_count) {
    std::vector<BendTriplet> t;
    t.reserve(elements.size() * 16);
    for (const BendElement& e : elements)
        for (std::size_t a = 0; a < 4; ++a)
            for (std::size_t b = 0; b < 4; ++b) {
                const double v = double(e.weight) * e.c[a] * e.c[b];
                if (v != 0.0 && e.v[a] < particle_count && e.v[b] < particle_count) t.push_back({e.v[a], e.v[b], v});
            }
    // Sort and sum duplicates in a fixed order (the same elements give the same bits).
    std::stable_sort(t.begin(), t.end(),
                     [](const BendTriplet& l, const BendTriplet& r) { return l.row != r.row ? l.row < r.row : l.col < r.col; });
    std::size_t out = 0;
    for (std::size_t k = 0; k < t.size(); ++k) {
        if (out > 0 && t[out - 1].row == t[k].row && t[out - 1].col == t[k].col)
            t[out - 1].value += t[k].value;
        else
            t[out++] = t[k];
    }
    t.resize(out);
    return t;
}

void set_bending(Cloth& cloth, std::vector<BendElement> elements, float damping) {
    const std::size_t n = cloth.particle_count;
    if (!(damping >= 0.0f) || !std::isfinite(damping))
        throw InvalidInput("bending damping = " + std::to_string(damping) + " s (must be finite and >= 0)");
    for (std::size_t k = 0; k < elements.size(); ++k) check_element(elements[k], k, n);

    BendingSet b;
    b.damping = damping;
    // Off-diagonal Q per row (the diagonal follows from the zero row sum), assembled row by row from each particle's
    // elements (a few hundred bytes per particle at most, not the 16 triplets per element of bending_hessian). The
    // terms of an entry are summed in element order, then slot order: the same sums as bending_hessian.
    std::vector<std::uint32_t> inc_offsets(n + 1, 0), inc;
    auto for_each_particle_once = [&](const BendElement& e, auto&& f) {
        for (std::size_t a = 0; a < 4; ++a) {
            if (e.c[a] == 0.0f) continue;
            bool seen = false;
            for (std::size_t b = 0; b < a; ++b) seen = seen || (e.c[b] != 0.0f && e.v[b] == e.v[a]);
            if (!seen) f(e.v[a]);
        }
    };
    for (const BendElement& e : elements) for_each_particle_once(e, [&](std::uint32_t i) { ++inc_offsets[i + 1]; });
    for (std::size_t i = 0; i < n; ++i) inc_offsets[i + 1] += inc_offsets[i];
    inc.resize(inc_offsets[n]);
    {
        std::vector<std::uint32_t> fill(inc_offsets.begin(), inc_offsets.end() - 1);
        for (std::uint32_t k = 0; k < elements.size(); ++k)
            for_each_particle_once(elements[k], [&](std::uint32_t i) { inc[fill[i]++] = k; });
    }
    b.offsets.assign(n + 1, 0);
    std::vector<std::pair<std::uint32_t, double>> row;
    for (std::size_t i = 0; i < n; ++i) {
        row.clear();
        for (std::uint32_t k = inc_offsets[i]; k < inc_offsets[i + 1]; ++k) {
            const BendElement& e = elements[inc[k]];
            for (std::size_t a = 0; a < 4; ++a) {
                if (e.v[a] != i) continue;
                for (std::size_t c2 = 0; c2 < 4; ++c2) {
                    const double v = double(e.weight) * e.c[a] * e.c[c2];
                    if (v != 0.0 && e.v[c2] != i) row.emplace_back(e.v[c2], v);
                }
            }
        }
        std::stable_sort(row.begin(), row.end(), [](const auto& l, const auto& r) { return l.first < r.first; });
        for (std::size_t k = 0; k < row.size(); ++k) {
            if (k > 0 && row[k].first == row[k - 1].first) {
                b.value.back() += row[k].second;
            } else {
                b.neighbour.push_back(row[k].first);
                b.value.push_back(row[k].second);
            }
        }
        b.offsets[i + 1] = static_cast<std::uint32_t>(b.neighbour.size());
    }
    // A mirror-exact cloth (mirror_symmetry.hpp): a particle after its twin takes the twin's coefficients, a particle on
    // the centre line the same coefficient for a neighbour and its twin (the terms' sums differ in rounding).
    const std::vector<std::uint32_t>& twin = cloth.mirror;
    if (!twin.empty()) {
        auto at = [&](std::uint32_t i, std::uint32_t j) {
            const auto first = b.neighbour.begin() + b.offsets[i], last = b.neighbour.begin() + b.offsets[i + 1];
            const auto it = std::lower_bound(first, last, j);
            if (it == last || *it != j)
                throw InvalidInput("mirror map: bending couples particles " + std::to_string(twin[i]) + " and " +
                                   std::to_string(twin[j]) + " but not their twins " + std::to_string(i) + " and " +
                                   std::to_string(j) + " (the mesh is not its own mirror image)");
            return static_cast<std::size_t>(it - b.neighbour.begin());
        };
        for (std::uint32_t i = 0; i < n; ++i)
            for (std::uint32_t k = b.offsets[i]; k < b.offsets[i + 1]; ++k) {
                const std::uint32_t j = b.neighbour[k];
                if (twin[i] < i) b.value[k] = b.value[at(twin[i], twin[j])];
                else if (twin[i] == i && twin[j] < j) b.value[k] = b.value[at(i, twin[j])];
            }
    }

    // SELL-C over the padded particle range, as SpringGraph (spring_graph.hpp).
    constexpr std::size_t C = simd::width;
    const std::size_t slices = cloth.padded_count / C;
    const std::size_t total = sell_slices(b.offsets, n, cloth.padded_count, b.slice_begin, b.slice_slots);
    // With a mirror map, each particle's slots are filled in mirror order (mirror_symmetry.hpp), else in CSR order.
    const std::vector<std::uint32_t> from =
        twin.empty() ? std::vector<std::uint32_t>{} : mirror_row_sources(b.offsets, b.neighbour, twin, twin);
    b.sell_neighbour.reset(total);
    b.sell_coefficient.reset(total);
    for (std::size_t s = 0; s < slices; ++s)
        for (std::size_t lane = 0; lane < C; ++lane) {
            const std::size_t i = s * C + lane;
            const std::uint32_t len = i < n ? b.offsets[i + 1] - b.offsets[i] : 0;
            for (std::uint32_t slot = 0; slot < b.slice_slots[s]; ++slot) {
                const std::size_t at = b.slice_begin[s] + slot * C + lane;
                if (slot < len) {
                    const std::uint32_t k = from.empty() ? b.offsets[i] + slot : from[b.offsets[i] + slot];
                    b.sell_neighbour[at] = b.neighbour[k];
                    b.sell_coefficient[at] = static_cast<float>(-b.value[k]);
                } else {
                    b.sell_neighbour[at] = static_cast<std::uint32_t>(i); // inert: zero difference, zero coefficient
                }
            }
        }
    b.elements = std::move(elements);
    cloth.bending = std::move(b);
}

double bending_energy(std::span<const BendElement> elements, std::span<const float> x, std::span<const float> y,
                      std::span<const float> z) {
    double e = 0.0;
    for (const BendElement& el : elements) {
        const std::array<double, 3> q = element_q(el, x, y, z);
        e += 0.5 * double(el.weight) * (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
    }
    return e;
}

BendGradient bending_gradient(std::span<const BendElement> elements, std::span<const float> x,
                              std::span<const float> y, std::span<const float> z) {
    const std::size_t n = x.size();
    BendGradient g{std::vector<double>(n, 0.0), std::vector<double>(n, 0.0), std::vector<double>(n, 0.0)};
    for (const BendElement& el : elements) {
        const std::array<double, 3> q = element_q(el, x, y, z);
        for (std::size_t k = 0; k < 4; ++k) {
            const double wc = double(el.weight) * el.c[k];
            g.gx[el.v[k]] += wc * q[0];
            g.gy[el.v[k]] += wc * q[1];
            g.gz[el.v[k]] += wc * q[2];
        }
    }
    return g;
}

GridBending grid_bending_weights(float h, float bend_u, float bend_v) {
    // Energy density 1/2 B_u k_uu^2 + 1/2 B_v k_vv^2 + B_t k_uv^2 with k ~ q / h^2 over an area A = h^2:
    // 1/2 (B A / h^4) |q|^2, so w = B / h^2; the twist term has no 1/2: w = 2 B_t / h^2.
    const double h2 = double(h) * h, bt = std::sqrt(double(bend_u) * bend_v);
    return {static_cast<float>(bend_u / h2), static_cast<float>(bend_v / h2), static_cast<float>(2.0 * bt / h2)};
}

std::vector<BendElement> grid_bending_elements(std::uint32_t columns, std::uint32_t rows, float h, float bend_u,
                                               float bend_v) {
    const GridBending w = grid_bending_weights(h, bend_u, bend_v);
    std::vector<BendElement> out;
    auto at = [&](std::uint32_t i, std::uint32_t j) { return j * columns + i; };
    for (std::uint32_t j = 0; j < rows; ++j)
        for (std::uint32_t i = 1; i + 1 < columns; ++i) {
            const float weight = j == 0 || j + 1 == rows ? 0.5f * w.u : w.u;
            out.push_back({{at(i - 1, j), at(i, j), at(i + 1, j), at(i, j)}, {1.0f, -2.0f, 1.0f, 0.0f}, weight});
        }
    for (std::uint32_t i = 0; i < columns; ++i)
        for (std::uint32_t j = 1; j + 1 < rows; ++j) {
            const float weight = i == 0 || i + 1 == columns ? 0.5f * w.v : w.v;
            out.push_back({{at(i, j - 1), at(i, j), at(i, j + 1), at(i, j)}, {1.0f, -2.0f, 1.0f, 0.0f}, weight});
        }
    for (std::uint32_t j = 0; j + 1 < rows; ++j)
        for (std::uint32_t i = 0; i + 1 < columns; ++i)
            out.push_back({{at(i, j), at(i + 1, j), at(i, j + 1), at(i + 1, j + 1)}, {1.0f, -1.0f, -1.0f, 1.0f}, w.twist});
    return out;
}

std::vector<double> bending_row_sums(const BendingSet& bending, std::size_t particle_count) {
    std::vector<double> sums(particle_count, 0.0);
    if (bending.offsets.size() != particle_count + 1) return sums;
    for (std::size_t i = 0; i < particle_count; ++i) {
        double off = 0.0, diag = 0.0;
        for (std::uint32_t k = bending.offsets[i]; k < bending.offsets[i + 1]; ++k) {
            off += std::fabs(bending.value[k]);
            diag -= bending.value[k];
        }
        sums[i] = std::fabs(diag) + off;
    }
    return sums;
}

} // namespace drape
