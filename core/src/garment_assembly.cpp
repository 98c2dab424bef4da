// Garment assembly: the particles, springs and triangles that panels append to, and the springs of a triangle mesh.
#include "drape/garment_assembly.hpp"

#include <algorithm>
#include <cmath>
#include <unordered_set>
#include <vector>

#include "panel_build.hpp"

namespace drape {

using namespace panel_build;

std::vector<float> GarmentAssembly::inverse_masses() const {
    std::vector<float> inv(mass.size());
    for (std::size_t i = 0; i < mass.size(); ++i)
        inv[i] = 1.0f / mass[i];
    return inv;
}

InitialState GarmentAssembly::initial_state() const {
    InitialState s;
    s.x = x;
    s.y = y;
    s.z = z;
    s.vx.assign(x.size(), 0.0f);
    s.vy.assign(x.size(), 0.0f);
    s.vz.assign(x.size(), 0.0f);
    return s;
}

std::size_t GarmentAssembly::edge_count(SpringKind kind) const noexcept {
    return static_cast<std::size_t>(
        std::count_if(edges.begin(), edges.end(), [kind](const Edge& e) { return e.kind == kind; }));
}


void add_triangle_springs(GarmentAssembly& io, std::span<const std::uint32_t> triangles) {
    struct HalfEdge {
        std::uint64_t key;
        std::uint32_t opposite;
    };
    std::vector<HalfEdge> half;
    half.reserve(triangles.size());
    for (std::size_t t = 0; t + 2 < triangles.size(); t += 3)
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t a = triangles[t + k], b = triangles[t + (k + 1) % 3], c = triangles[t + (k + 2) % 3];
            half.push_back({pair_key(a, b), c});
        }
    std::sort(half.begin(), half.end(), [](const HalfEdge& l, const HalfEdge& r) {
        return l.key != r.key ? l.key < r.key : l.opposite < r.opposite;
    });
    auto dist = [&](std::uint32_t a, std::uint32_t b) {
        const double dx = double{io.x[a]} - io.x[b], dy = double{io.y[a]} - io.y[b],
                     dz = double{io.z[a]} - io.z[b];
        return static_cast<float>(std::sqrt(dx * dx + dy * dy + dz * dz));
    };
    std::unordered_set<std::uint64_t> joined;
    joined.reserve(half.size());
    std::vector<std::uint64_t> cross;
    for (std::size_t k = 0; k < half.size();) {
        std::size_t m = k;
        while (m < half.size() && half[m].key == half[k].key)
            ++m;
        const auto a = static_cast<std::uint32_t>(half[k].key >> 32);
        const auto b = static_cast<std::uint32_t>(half[k].key & 0xffffffffu);
        io.edges.push_back({a, b, SpringKind::structural, dist(a, b)});
        joined.insert(half[k].key);
        if (m - k == 2 && half[k].opposite != half[k + 1].opposite)
            cross.push_back(pair_key(half[k].opposite, half[k + 1].opposite));
        k = m;
    }
    for (std::uint64_t key : cross) {
        if (!joined.insert(key).second) continue;
        const auto a = static_cast<std::uint32_t>(key >> 32);
        const auto b = static_cast<std::uint32_t>(key & 0xffffffffu);
        io.edges.push_back({a, b, SpringKind::bend, dist(a, b)});
    }
}

} // namespace drape
