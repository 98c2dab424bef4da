// Seams between pattern pieces: two polylines of particles joined by seam springs by normalised arc length.
#include "drape/pattern_seams.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <unordered_set>
#include <vector>

#include "panel_build.hpp"

namespace drape {

using namespace panel_build;

std::vector<std::uint32_t> sew_by_arc_length(GarmentAssembly& io, std::span<const std::uint32_t> a,
                                             std::span<const std::uint32_t> b, float seam_rest) {
    if (!(seam_rest > 0.0f) || !std::isfinite(seam_rest))
        throw InvalidInput("seam rest length = " + std::to_string(seam_rest) + " m (must be > 0 and finite)");
    if (a.empty() || b.empty()) throw InvalidInput("sewing needs at least one particle on each side");
    const std::size_t n = io.particle_count();
    for (std::span<const std::uint32_t> side : {a, b})
        for (std::uint32_t i : side)
            if (i >= n)
                throw InvalidInput("sewing names particle " + std::to_string(i) + " outside [0, " +
                                   std::to_string(n == 0 ? 0 : n - 1) + "]");
    // Normalised arc length along each polyline, from the assembly's positions.
    auto param = [&](std::span<const std::uint32_t> line) {
        std::vector<double> t(line.size(), 0.0);
        for (std::size_t k = 1; k < line.size(); ++k) {
            const double dx = double{io.x[line[k]]} - io.x[line[k - 1]],
                         dy = double{io.y[line[k]]} - io.y[line[k - 1]],
                         dz = double{io.z[line[k]]} - io.z[line[k - 1]];
            t[k] = t[k - 1] + std::sqrt(dx * dx + dy * dy + dz * dz);
        }
        if (t.back() > 0)
            for (double& v : t)
                v /= t.back();
        return t;
    };
    const std::vector<double> ta = param(a), tb = param(b);
    // Nearest entry of sorted `t` to `value` (the lower index on a tie).
    auto nearest = [](const std::vector<double>& t, double value) {
        const auto it = std::lower_bound(t.begin(), t.end(), value);
        std::size_t k = static_cast<std::size_t>(it - t.begin());
        if (k == t.size()) return t.size() - 1;
        if (k > 0 && value - t[k - 1] <= t[k] - value) return k - 1;
        return k;
    };
    std::unordered_set<std::uint64_t> joined;
    joined.reserve(io.edges.size() + a.size() + b.size());
    for (const Edge& e : io.edges)
        joined.insert(pair_key(e.a, e.b));
    std::vector<std::uint32_t> added;
    auto join = [&](std::uint32_t p, std::uint32_t q) {
        if (p == q || !joined.insert(pair_key(p, q)).second) return;
        added.push_back(static_cast<std::uint32_t>(io.edges.size()));
        io.edges.push_back({std::min(p, q), std::max(p, q), SpringKind::seam, seam_rest});
    };
    std::vector<std::uint8_t> b_joined(b.size(), 0);
    for (std::size_t k = 0; k < a.size(); ++k) {
        const std::size_t m = nearest(tb, ta[k]);
        b_joined[m] = 1;
        join(a[k], b[m]);
    }
    for (std::size_t m = 0; m < b.size(); ++m)
        if (!b_joined[m]) join(a[nearest(ta, tb[m])], b[m]);
    return added;
}

} // namespace drape
