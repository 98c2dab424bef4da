// Bowyer-Watson Delaunay triangulation on an exact integer lattice (the outline panels' mesher).
#include "drape/delaunay.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>
#include <vector>

#include "drape/errors.hpp"

namespace drape {

namespace {

using i64 = std::int64_t;
__extension__ typedef __int128 i128; // GCC/Clang 128-bit integer (exact in-circle test)

constexpr i64 lattice_max = (i64{1} << 28) - 1; // input points snap to [0, 2^28)

struct LatticePoint {
    i64 x, y;
};

// > 0 when (a, b, c) turn counter-clockwise. Exact: coordinates < 2^28, products < 2^56.
inline i64 orient(const LatticePoint& a, const LatticePoint& b, const LatticePoint& c) noexcept {
    return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

// > 0 when d is strictly inside the circumcircle of the counter-clockwise triangle (a, b, c). Exact in 128
// bits: differences < 2^28, lifted terms < 2^57, each product < 2^115.
inline int in_circle(const LatticePoint& a, const LatticePoint& b, const LatticePoint& c,
                     const LatticePoint& d) noexcept {
    const i64 adx = a.x - d.x, ady = a.y - d.y, bdx = b.x - d.x, bdy = b.y - d.y, cdx = c.x - d.x,
              cdy = c.y - d.y;
    const i128 alift = i128{adx} * adx + i128{ady} * ady;
    const i128 blift = i128{bdx} * bdx + i128{bdy} * bdy;
    const i128 clift = i128{cdx} * cdx + i128{cdy} * cdy;
    const i128 det = alift * (i128{bdx} * cdy - i128{cdx} * bdy) +
                     blift * (i128{cdx} * ady - i128{adx} * cdy) +
                     clift * (i128{adx} * bdy - i128{bdx} * ady);
    return det > 0 ? 1 : (det < 0 ? -1 : 0);
}

// Index along a Hilbert curve over a 2^20 x 2^20 grid (insertion order with locality).
std::uint64_t hilbert_index(std::uint32_t x, std::uint32_t y) noexcept {
    constexpr std::uint32_t n = 1u << 20;
    std::uint64_t d = 0;
    for (std::uint32_t s = n / 2; s > 0; s /= 2) {
        const std::uint32_t rx = (x & s) ? 1u : 0u, ry = (y & s) ? 1u : 0u;
        d += std::uint64_t{s} * s * ((3u * rx) ^ ry);
        if (ry == 0) {
            if (rx == 1) {
                x = n - 1 - x;
                y = n - 1 - y;
            }
            std::swap(x, y);
        }
    }
    return d;
}

struct Triangle {
    std::uint32_t v[3];  // counter-clockwise; a ghost triangle has the vertex at infinity in v[2]
    std::int32_t adj[3]; // adj[i]: triangle across the edge opposite v[i] (v[i+1] -> v[i+2])
};

constexpr std::uint32_t dead = std::numeric_limits<std::uint32_t>::max();

// Bowyer-Watson with the super-triangle taken to infinity: one symbolic vertex `inf` and "ghost" triangles
// (a, b, inf) on every convex-hull edge a -> b (the hull lies to its right). A ghost's circumcircle is the
// open half-plane left of a -> b plus the open segment ab (J. R. Shewchuk's lecture notes on Delaunay
// refinement). So the triangulation always covers exactly the convex hull: no sliver is lost to a finite
// super-triangle.
class BowyerWatson {
  public:
    // Starts from the counter-clockwise triangle (p0, p1, p2) and its three ghosts.
    BowyerWatson(std::vector<LatticePoint> points, std::uint32_t p0, std::uint32_t p1, std::uint32_t p2)
        : pts_(std::move(points)), inf_(static_cast<std::uint32_t>(pts_.size())) {
        tris_.push_back({{p0, p1, p2}, {-1, -1, -1}});
        tris_.push_back({{p2, p1, inf_}, {-1, -1, -1}});
        tris_.push_back({{p0, p2, inf_}, {-1, -1, -1}});
        tris_.push_back({{p1, p0, inf_}, {-1, -1, -1}});
        for (std::int32_t t = 0; t < 4; ++t)
            for (std::int32_t u = 0; u < 4; ++u)
                for (int i = 0; i < 3; ++i)
                    if (u != t && has_edge(u, tris_[t].v[(i + 2) % 3], tris_[t].v[(i + 1) % 3]))
                        tris_[t].adj[i] = u;
        stamp_.assign(4, 0);
    }

    void insert(std::uint32_t p) {
        ++round_;
        const std::int32_t start = locate(pts_[p]);
        // Cavity: triangles whose circumcircle strictly contains p, flooded from the one holding p.
        cavity_.clear();
        boundary_.clear();
        cavity_.push_back(start);
        stamp_[start] = in_stamp();
        for (std::size_t k = 0; k < cavity_.size(); ++k) {
            const std::int32_t t = cavity_[k];
            for (int i = 0; i < 3; ++i) {
                const std::int32_t nb = tris_[t].adj[i];
                if (stamp_[nb] == in_stamp()) continue;
                if (stamp_[nb] != out_stamp()) {
                    if (circumcircle_contains(nb, p)) {
                        stamp_[nb] = in_stamp();
                        cavity_.push_back(nb);
                        continue;
                    }
                    stamp_[nb] = out_stamp();
                }
                boundary_.push_back({tris_[t].v[(i + 1) % 3], tris_[t].v[(i + 2) % 3], nb});
            }
        }
        for (std::int32_t t : cavity_) {
            tris_[t].v[0] = dead;
            free_.push_back(t);
        }
        // Fan: one triangle (a, b, p) per boundary edge a -> b (rotated so a vertex at infinity comes last).
        fan_.clear();
        for (const BoundaryEdge& e : boundary_) {
            std::int32_t t;
            if (!free_.empty()) {
                t = free_.back();
                free_.pop_back();
            } else {
                t = static_cast<std::int32_t>(tris_.size());
                tris_.push_back({});
                stamp_.push_back(0);
            }
            if (e.a == inf_)
                tris_[t] = {{e.b, p, inf_}, {-1, -1, -1}};
            else if (e.b == inf_)
                tris_[t] = {{p, e.a, inf_}, {-1, -1, -1}};
            else
                tris_[t] = {{e.a, e.b, p}, {-1, -1, -1}};
            stamp_[t] = 0;
            set_adj(t, e.a, e.b, e.outside);
            set_adj(e.outside, e.b, e.a, t);
            fan_.push_back({e.a, t});
        }
        // The cavity boundary is a simple polygon around p: each of its vertices starts exactly one boundary
        // edge. Edge b -> p of the triangle on a -> b faces edge p -> b of the triangle on b -> c.
        std::sort(fan_.begin(), fan_.end());
        for (std::size_t k = 0; k < fan_.size(); ++k) {
            const std::int32_t t = fan_[k].second;
            const std::uint32_t b = boundary_of(t, p);
            const auto it = std::lower_bound(fan_.begin(), fan_.end(),
                                             std::pair<std::uint32_t, std::int32_t>{b, INT32_MIN});
            set_adj(t, b, p, it->second);
            set_adj(it->second, p, b, t);
        }
        last_ = fan_.front().second;
    }

    // Real triangles (no vertex at infinity), 3 indices each.
    std::vector<std::uint32_t> result() const {
        std::vector<std::uint32_t> out;
        for (const Triangle& t : tris_) {
            if (t.v[0] == dead || t.v[2] == inf_) continue;
            out.insert(out.end(), {t.v[0], t.v[1], t.v[2]});
        }
        return out;
    }

  private:
    struct BoundaryEdge {
        std::uint32_t a, b;
        std::int32_t outside;
    };

    std::uint64_t in_stamp() const noexcept { return 2 * round_; }
    std::uint64_t out_stamp() const noexcept { return 2 * round_ + 1; }
    bool is_ghost(std::int32_t t) const noexcept { return tris_[t].v[2] == inf_; }

    bool has_edge(std::int32_t t, std::uint32_t u, std::uint32_t v) const noexcept {
        for (int i = 0; i < 3; ++i)
            if (tris_[t].v[(i + 1) % 3] == u && tris_[t].v[(i + 2) % 3] == v) return true;
        return false;
    }
    void set_adj(std::int32_t t, std::uint32_t u, std::uint32_t v, std::int32_t nb) noexcept {
        for (int i = 0; i < 3; ++i)
            if (tris_[t].v[(i + 1) % 3] == u && tris_[t].v[(i + 2) % 3] == v) tris_[t].adj[i] = nb;
    }
    // For a fan triangle built on boundary edge a -> b around p: b (the vertex before p in counter-clockwise
    // order).
    std::uint32_t boundary_of(std::int32_t t, std::uint32_t p) const noexcept {
        const Triangle& tri = tris_[t];
        for (int i = 0; i < 3; ++i)
            if (tri.v[(i + 1) % 3] == p) return tri.v[i];
        return dead;
    }

    bool circumcircle_contains(std::int32_t t, std::uint32_t p) const noexcept {
        const Triangle& tri = tris_[t];
        const LatticePoint& q = pts_[p];
        if (tri.v[2] != inf_) return in_circle(pts_[tri.v[0]], pts_[tri.v[1]], pts_[tri.v[2]], q) > 0;
        const LatticePoint& a = pts_[tri.v[0]];
        const LatticePoint& b = pts_[tri.v[1]];
        const i64 o = orient(a, b, q);
        if (o != 0) return o > 0;
        // On the hull edge's line: inside only on the open segment.
        return (q.x - a.x) * (b.x - a.x) + (q.y - a.y) * (b.y - a.y) > 0 &&
               (q.x - b.x) * (a.x - b.x) + (q.y - b.y) * (a.y - b.y) > 0;
    }

    // Visibility walk from the last created triangle to a real triangle containing q (inside or on its
    // boundary), or to the ghost whose half-plane holds q when q is outside the hull. Terminates on a
    // Delaunay triangulation; the first edge tried rotates so the walk never cycles on degenerate layouts.
    std::int32_t locate(const LatticePoint& q) const {
        std::int32_t t = last_;
        if (is_ghost(t)) {
            if (orient(pts_[tris_[t].v[0]], pts_[tris_[t].v[1]], q) > 0) return t;
            t = tris_[t].adj[2];
        }
        for (std::size_t step = 0;; ++step) {
            const Triangle& tri = tris_[t];
            bool moved = false;
            for (int k = 0; k < 3; ++k) {
                const int i = static_cast<int>((k + step) % 3);
                if (orient(pts_[tri.v[(i + 1) % 3]], pts_[tri.v[(i + 2) % 3]], q) < 0) {
                    t = tri.adj[i];
                    moved = true;
                    break;
                }
            }
            if (!moved || is_ghost(t)) return t;
            if (step > 4 * tris_.size() + 16) throw std::logic_error("delaunay: point location failed");
        }
    }

    std::vector<LatticePoint> pts_;
    std::uint32_t inf_;
    std::vector<Triangle> tris_;
    std::vector<std::uint64_t> stamp_;
    std::vector<std::int32_t> free_, cavity_;
    std::vector<BoundaryEdge> boundary_;
    std::vector<std::pair<std::uint32_t, std::int32_t>> fan_;
    std::uint64_t round_ = 0;
    std::int32_t last_ = 0;
};

} // namespace

std::vector<std::uint32_t> delaunay_triangulate(std::span<const double> px, std::span<const double> py,
                                                std::vector<std::uint32_t>* out_duplicate_of) {
    if (px.size() != py.size())
        throw InvalidInput("delaunay: " + std::to_string(px.size()) + " x coordinates but " +
                           std::to_string(py.size()) + " y coordinates");
    const std::size_t n = px.size();
    if (n > (std::size_t{1} << 24))
        throw InvalidInput("delaunay: " + std::to_string(n) + " points (allowed 0..16777216)");
    double min_x = 0, max_x = 0, min_y = 0, max_y = 0;
    for (std::size_t i = 0; i < n; ++i) {
        if (!std::isfinite(px[i]) || !std::isfinite(py[i]))
            throw InvalidInput("delaunay: point " + std::to_string(i) + " has a non-finite coordinate");
        if (i == 0 || px[i] < min_x) min_x = px[i];
        if (i == 0 || px[i] > max_x) max_x = px[i];
        if (i == 0 || py[i] < min_y) min_y = py[i];
        if (i == 0 || py[i] > max_y) max_y = py[i];
    }
    const double extent = std::max(max_x - min_x, max_y - min_y);
    const double scale = extent > 0 ? static_cast<double>(lattice_max) / extent : 0.0;
    std::vector<LatticePoint> lattice(n);
    for (std::size_t i = 0; i < n; ++i)
        lattice[i] = {std::min<i64>(std::llround((px[i] - min_x) * scale), lattice_max),
                      std::min<i64>(std::llround((py[i] - min_y) * scale), lattice_max)};

    // Merge points that share a lattice point (the lowest index stays).
    std::vector<std::uint32_t> order(n);
    std::iota(order.begin(), order.end(), 0u);
    std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
        if (lattice[a].x != lattice[b].x) return lattice[a].x < lattice[b].x;
        if (lattice[a].y != lattice[b].y) return lattice[a].y < lattice[b].y;
        return a < b;
    });
    std::vector<std::uint32_t> dup(n);
    std::vector<std::uint32_t> unique;
    for (std::size_t k = 0; k < n; ++k) {
        const std::uint32_t i = order[k];
        if (k > 0 && lattice[i].x == lattice[order[k - 1]].x && lattice[i].y == lattice[order[k - 1]].y) {
            dup[i] = dup[order[k - 1]];
        } else {
            dup[i] = i;
            unique.push_back(i);
        }
    }
    if (out_duplicate_of) *out_duplicate_of = dup;
    if (unique.size() < 3) return {};

    // Insertion order: along a Hilbert curve (ties by index: deterministic).
    std::vector<std::uint64_t> key(n);
    for (std::uint32_t i : unique)
        key[i] = hilbert_index(static_cast<std::uint32_t>(lattice[i].x >> 8),
                               static_cast<std::uint32_t>(lattice[i].y >> 8));
    std::sort(unique.begin(), unique.end(),
              [&](std::uint32_t a, std::uint32_t b) { return key[a] != key[b] ? key[a] < key[b] : a < b; });
    std::vector<LatticePoint> pts(unique.size());
    for (std::size_t k = 0; k < unique.size(); ++k)
        pts[k] = lattice[unique[k]];
    // The first triangle: the first two points and the first point after them not collinear with them.
    std::uint32_t third = 2;
    while (third < pts.size() && orient(pts[0], pts[1], pts[third]) == 0)
        ++third;
    if (third == pts.size()) return {}; // all collinear
    const bool ccw = orient(pts[0], pts[1], pts[third]) > 0;
    BowyerWatson bw(pts, 0, ccw ? 1u : third, ccw ? third : 1u);
    for (std::uint32_t k = 1; k < pts.size(); ++k)
        if (k != third && k != 1) bw.insert(k);
    const std::vector<std::uint32_t> lattice_tris = bw.result();
    // Drop slivers thinner than 4 lattice quanta (judged on the input coordinates): nearly collinear hull
    // points give them, and rounding to the lattice may have turned them inside out.
    const double quantum = extent / static_cast<double>(lattice_max);
    std::vector<std::uint32_t> tris;
    tris.reserve(lattice_tris.size());
    for (std::size_t t = 0; t < lattice_tris.size(); t += 3) {
        const std::uint32_t a = unique[lattice_tris[t]], b = unique[lattice_tris[t + 1]],
                            c = unique[lattice_tris[t + 2]];
        const double o = (px[b] - px[a]) * (py[c] - py[a]) - (py[b] - py[a]) * (px[c] - px[a]);
        const double longest =
            std::max({std::hypot(px[b] - px[a], py[b] - py[a]), std::hypot(px[c] - px[b], py[c] - py[b]),
                      std::hypot(px[a] - px[c], py[a] - py[c])});
        if (o <= 4.0 * quantum * longest) continue; // height = o / longest
        tris.insert(tris.end(), {a, b, c});
    }
    return tris;
}

} // namespace drape
