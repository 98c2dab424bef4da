// Bowyer-Watson Delaunay: empty circumcircles, counter-clockwise triangles, hull coverage, degenerate inputs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include "drape/errors.hpp"
#include "drape/delaunay.hpp"

namespace drape {
namespace {

struct Points {
    std::vector<double> x, y;
};

double orient(const Points& p, std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    return (p.x[b] - p.x[a]) * (p.y[c] - p.y[a]) - (p.y[b] - p.y[a]) * (p.x[c] - p.x[a]);
}

// Area of the convex hull (Andrew's monotone chain).
double hull_area(const Points& p) {
    std::vector<std::uint32_t> idx(p.x.size());
    std::iota(idx.begin(), idx.end(), 0u);
    std::sort(idx.begin(), idx.end(),
              [&](auto a, auto b) { return p.x[a] != p.x[b] ? p.x[a] < p.x[b] : p.y[a] < p.y[b]; });
    std::vector<std::uint32_t> h(2 * idx.size());
    std::size_t k = 0;
    for (std::size_t i = 0; i < idx.size(); ++i) {
        while (k >= 2 && orient(p, h[k - 2], h[k - 1], idx[i]) <= 0)
            --k;
        h[k++] = idx[i];
    }
    for (std::size_t i = idx.size() - 1, t = k + 1; i > 0; --i) {
        while (k >= t && orient(p, h[k - 2], h[k - 1], idx[i - 1]) <= 0)
            --k;
        h[k++] = idx[i - 1];
    }
    double s = 0;
    for (std::size_t i = 0; i + 1 < k; ++i)
        s += p.x[h[i]] * p.y[h[i + 1]] - p.x[h[i + 1]] * p.y[h[i]];
    return 0.5 * s;
}

// Checks every triangle: counter-clockwise and no point strictly inside its circumcircle (tolerance: the
// triangulation is exact on points snapped to a 2^28 lattice over the bounding box, so co-circular points may
// come out either way within a few lattice quanta, ~4e-9 of the extent). Brute force. Returns the total area.
double check_delaunay(const Points& p, const std::vector<std::uint32_t>& tris, double scale) {
    double area = 0;
    const double tol = 1e-7 * scale;
    for (std::size_t t = 0; t < tris.size(); t += 3) {
        const std::uint32_t a = tris[t], b = tris[t + 1], c = tris[t + 2];
        const double o = orient(p, a, b, c);
        EXPECT_GT(o, 0.0) << "triangle " << t / 3 << " is not counter-clockwise";
        area += 0.5 * o;
        // Circumcentre.
        const double bx = p.x[b] - p.x[a], by = p.y[b] - p.y[a], cx = p.x[c] - p.x[a], cy = p.y[c] - p.y[a];
        const double d = 2 * (bx * cy - by * cx);
        const double ux = (cy * (bx * bx + by * by) - by * (cx * cx + cy * cy)) / d;
        const double uy = (bx * (cx * cx + cy * cy) - cx * (bx * bx + by * by)) / d;
        const double r = std::hypot(ux, uy);
        for (std::size_t i = 0; i < p.x.size(); ++i) {
            const double di = std::hypot(p.x[i] - p.x[a] - ux, p.y[i] - p.y[a] - uy);
            if (di < r - tol) {
                ADD_FAILURE() << "point " << i << " is inside the circumcircle of triangle " << t / 3
                              << " by " << r - di;
                return area;
            }
        }
    }
    return area;
}

TEST(Delaunay, RandomPointsHaveEmptyCircumcirclesAndCoverTheHull) {
    for (unsigned seed : {1u, 2u, 3u, 4u, 5u, 6u}) {
        std::mt19937 rng(seed);
        std::uniform_real_distribution<double> u(-1.0, 1.0);
        const std::size_t n = 200 + 300 * seed;
        Points p;
        for (std::size_t i = 0; i < n; ++i) {
            p.x.push_back(u(rng));
            p.y.push_back(u(rng) * 0.5 + 3.0);
        }
        const auto tris = delaunay_triangulate(p.x, p.y);
        SCOPED_TRACE("seed " + std::to_string(seed));
        const double area = check_delaunay(p, tris, 2.0);
        EXPECT_NEAR(area, hull_area(p), 1e-9);
        // Every point is a vertex of some triangle.
        std::vector<int> used(n, 0);
        for (auto v : tris)
            used[v] = 1;
        EXPECT_EQ(std::count(used.begin(), used.end(), 1), static_cast<long>(n));
    }
}

TEST(Delaunay, GridsWithCoCircularPoints) {
    // Axis-aligned, rotated and offset grids: every square's four corners are co-circular.
    for (double angle : {0.0, 0.3, M_PI / 4}) {
        for (std::size_t n : {2u, 3u, 10u, 33u}) {
            Points p;
            for (std::size_t j = 0; j < n; ++j)
                for (std::size_t i = 0; i < n; ++i) {
                    const double x = 0.1 * static_cast<double>(i) + 5.0,
                                 y = 0.1 * static_cast<double>(j) - 2.0;
                    p.x.push_back(std::cos(angle) * x - std::sin(angle) * y);
                    p.y.push_back(std::sin(angle) * x + std::cos(angle) * y);
                }
            const auto tris = delaunay_triangulate(p.x, p.y);
            SCOPED_TRACE("n " + std::to_string(n) + " angle " + std::to_string(angle));
            EXPECT_EQ(tris.size() / 3, 2 * (n - 1) * (n - 1));
            const double area = check_delaunay(p, tris, 0.1 * static_cast<double>(n));
            EXPECT_NEAR(area, 0.01 * static_cast<double>((n - 1) * (n - 1)), 1e-9);
            // Deterministic.
            EXPECT_EQ(delaunay_triangulate(p.x, p.y), tris);
        }
    }
    // A grid plus random points mixed in, and a hexagonal (triangular) lattice.
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    Points p;
    for (int j = 0; j < 20; ++j)
        for (int i = 0; i < 20; ++i) {
            p.x.push_back(i / 19.0);
            p.y.push_back(j / 19.0);
            p.x.push_back((i + 0.5 * (j % 2)) / 19.0 + 2.0);
            p.y.push_back(j * std::sqrt(0.75) / 19.0);
        }
    for (int k = 0; k < 200; ++k) {
        p.x.push_back(u(rng));
        p.y.push_back(u(rng));
    }
    const auto tris = delaunay_triangulate(p.x, p.y);
    const double area = check_delaunay(p, tris, 3.0);
    EXPECT_NEAR(area, hull_area(p), 1e-6);
}

TEST(Delaunay, PointsOnOneCircle) {
    Points p;
    const int n = 64;
    for (int k = 0; k < n; ++k) {
        p.x.push_back(std::cos(2 * M_PI * k / n));
        p.y.push_back(std::sin(2 * M_PI * k / n));
    }
    auto tris = delaunay_triangulate(p.x, p.y);
    EXPECT_EQ(tris.size() / 3, static_cast<std::size_t>(n - 2));
    check_delaunay(p, tris, 1.0);
    p.x.push_back(0.0); // and its centre
    p.y.push_back(0.0);
    tris = delaunay_triangulate(p.x, p.y);
    EXPECT_EQ(tris.size() / 3, static_cast<std::size_t>(n));
    EXPECT_NEAR(check_delaunay(p, tris, 1.0), hull_area(p), 1e-9);
}

TEST(Delaunay, DegenerateInputs) {
    EXPECT_TRUE(delaunay_triangulate({}, {}).empty());
    const std::vector<double> lx{0, 1, 2, 3}, ly{0, 1, 2, 3};
    EXPECT_TRUE(delaunay_triangulate(lx, ly).empty()); // collinear
    // Duplicates are merged into the lowest index.
    const std::vector<double> dx{0, 1, 0, 0, 1}, dy{0, 0, 1, 0, 0};
    std::vector<std::uint32_t> dup;
    const auto tris = delaunay_triangulate(dx, dy, &dup);
    ASSERT_EQ(tris.size(), 3u);
    EXPECT_EQ(dup, (std::vector<std::uint32_t>{0, 1, 2, 0, 1}));
    EXPECT_GT((dx[tris[1]] - dx[tris[0]]) * (dy[tris[2]] - dy[tris[0]]) -
                  (dy[tris[1]] - dy[tris[0]]) * (dx[tris[2]] - dx[tris[0]]),
              0.0);
    const std::vector<double> bad{0, NAN, 1};
    EXPECT_THROW(delaunay_triangulate(bad, dx), InvalidInput);
    EXPECT_THROW(delaunay_triangulate(lx, dy), InvalidInput); // different lengths
}

TEST(Delaunay, LargeGridIsFast) {
    // 250k points on a grid (co-circular everywhere): the walk and cavity stay local.
    Points p;
    const int n = 500;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            p.x.push_back(i * 0.002);
            p.y.push_back(j * 0.002);
        }
    const auto tris = delaunay_triangulate(p.x, p.y);
    EXPECT_EQ(tris.size() / 3, 2u * (n - 1) * (n - 1));
}

} // namespace
} // namespace drape
