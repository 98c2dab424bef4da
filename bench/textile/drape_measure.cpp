// Top-view raster, radial profile, fold count and picture of a draped cloth (see drape_measure.hpp).
#include "drape_measure.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <stb_image_write.h>

namespace drape::textile {

namespace {
constexpr double pi = 3.14159265358979323846;
constexpr float none = -std::numeric_limits<float>::infinity();
} // namespace

bool TopView::covered(int px, int pz) const { return top[static_cast<std::size_t>(pz) * size + px] != none; }

double TopView::area() const {
    std::size_t count = 0;
    for (float t : top) count += t != none;
    return double(count) * pixel * pixel;
}

TopView rasterise_top(std::span<const float> x, std::span<const float> y, std::span<const float> z,
                      std::span<const std::uint32_t> tri, double extent, double pixel) {
    TopView v;
    v.extent = extent;
    v.pixel = pixel;
    v.size = static_cast<int>(std::ceil(2.0 * extent / pixel));
    v.top.assign(static_cast<std::size_t>(v.size) * v.size, none);
    auto px_of = [&](double c) { return (c + extent) / pixel - 0.5; }; // pixel coordinate of a position
    for (std::size_t t = 0; t + 2 < tri.size(); t += 3) {
        const std::uint32_t a = tri[t], b = tri[t + 1], c = tri[t + 2];
        const double ax = px_of(x[a]), az = px_of(z[a]), bx = px_of(x[b]), bz = px_of(z[b]), cx = px_of(x[c]),
                     cz = px_of(z[c]);
        const double area2 = (bx - ax) * (cz - az) - (bz - az) * (cx - ax);
        if (std::fabs(area2) < 1e-12) continue; // seen edge-on: no shadow
        const int x0 = std::max(0, static_cast<int>(std::floor(std::min({ax, bx, cx}))));
        const int x1 = std::min(v.size - 1, static_cast<int>(std::ceil(std::max({ax, bx, cx}))));
        const int z0 = std::max(0, static_cast<int>(std::floor(std::min({az, bz, cz}))));
        const int z1 = std::min(v.size - 1, static_cast<int>(std::ceil(std::max({az, bz, cz}))));
        for (int pz = z0; pz <= z1; ++pz)
            for (int px = x0; px <= x1; ++px) {
                // Barycentric coordinates of the pixel centre; covered when all are >= 0 (either winding).
                const double wa = ((bx - px) * (cz - pz) - (bz - pz) * (cx - px)) / area2;
                const double wb = ((cx - px) * (az - pz) - (cz - pz) * (ax - px)) / area2;
                const double wc = 1.0 - wa - wb;
                if (wa < 0.0 || wb < 0.0 || wc < 0.0) continue;
                const float h = static_cast<float>(wa * y[a] + wb * y[b] + wc * y[c]);
                float& slot = v.top[static_cast<std::size_t>(pz) * v.size + px];
                slot = std::max(slot, h);
            }
    }
    return v;
}

std::vector<double> radial_profile(const TopView& v, int bins) {
    std::vector<double> r(bins, 0.0);
    for (int pz = 0; pz < v.size; ++pz)
        for (int px = 0; px < v.size; ++px) {
            if (!v.covered(px, pz)) continue;
            const double x = -v.extent + (px + 0.5) * v.pixel, z = -v.extent + (pz + 0.5) * v.pixel;
            const double phi = std::atan2(z, x) + pi;
            const int b = std::min(bins - 1, static_cast<int>(phi / (2.0 * pi) * bins));
            r[b] = std::max(r[b], std::hypot(x, z));
        }
    return r;
}

int fold_count(const std::vector<double>& profile, double band, int smooth) {
    const int n = static_cast<int>(profile.size());
    std::vector<double> s(n, 0.0);
    for (int i = 0; i < n; ++i) {
        for (int k = -smooth / 2; k <= smooth / 2; ++k) s[i] += profile[((i + k) % n + n) % n];
        s[i] /= smooth;
    }
    double mean = 0.0;
    for (double r : s) mean += r;
    mean /= n;
    // Start in a definite state (below or above the band), walk once around the circle.
    int start = 0;
    while (start < n && std::fabs(s[start] - mean) < band) ++start;
    if (start == n) return 0;
    bool above = s[start] > mean;
    int ups = 0;
    for (int k = 1; k <= n; ++k) {
        const double r = s[(start + k) % n];
        if (!above && r > mean + band) {
            above = true;
            ++ups;
        } else if (above && r < mean - band) {
            above = false;
        }
    }
    return ups;
}

bool write_top_view_png(const TopView& v, const std::string& path, double disc_radius, double specimen_radius) {
    float lo = std::numeric_limits<float>::infinity(), hi = -lo;
    for (float t : v.top)
        if (t != none) {
            lo = std::min(lo, t);
            hi = std::max(hi, t);
        }
    std::vector<unsigned char> rgb(static_cast<std::size_t>(v.size) * v.size * 3, 255);
    const double ring = 1.5 * v.pixel;
    for (int pz = 0; pz < v.size; ++pz)
        for (int px = 0; px < v.size; ++px) {
            unsigned char* p = &rgb[(static_cast<std::size_t>(pz) * v.size + px) * 3];
            const double x = -v.extent + (px + 0.5) * v.pixel, z = -v.extent + (pz + 0.5) * v.pixel;
            const double r = std::hypot(x, z);
            const float t = v.top[static_cast<std::size_t>(pz) * v.size + px];
            if (t != none) {
                const double f = hi > lo ? (t - lo) / (hi - lo) : 1.0; // 1 = highest
                p[0] = static_cast<unsigned char>(40 + 180 * f);
                p[1] = static_cast<unsigned char>(60 + 170 * f);
                p[2] = static_cast<unsigned char>(110 + 140 * f);
            }
            if (std::fabs(r - disc_radius) < ring) {
                p[0] = 220;
                p[1] = 30;
                p[2] = 30;
            } else if (std::fabs(r - specimen_radius) < ring && (static_cast<int>(std::atan2(z, x) * 90) & 1)) {
                p[0] = p[1] = p[2] = 120;
            }
        }
    return stbi_write_png(path.c_str(), v.size, v.size, 3, rgb.data(), v.size * 3) != 0;
}

} // namespace drape::textile
