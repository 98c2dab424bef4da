// Ray-sphere picking against every particle (see picking.hpp).
#include "drape/picking.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Dense>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "drape/errors.hpp"

namespace drape {

namespace {

/// Particles per picking block (fixed, so partial results combine in the same order for any thread count).
constexpr std::size_t pick_block = 16384;

/// Nearer hit first; the lower index on a tie.
bool nearer(const PickHit& a, const PickHit& b) noexcept {
    return a.distance < b.distance || (a.distance == b.distance && a.index < b.index);
}

} // namespace

Eigen::Vector2f window_to_ndc(double px, double py, double width, double height) noexcept {
    const double w = std::max(width, 1.0), h = std::max(height, 1.0);
    return {static_cast<float>(2.0 * px / w - 1.0), static_cast<float>(1.0 - 2.0 * py / h)};
}

Ray ray_from_ndc(const Eigen::Matrix4f& inverse_view_projection, float ndc_x, float ndc_y) {
    const Eigen::Vector4f near_h = inverse_view_projection * Eigen::Vector4f(ndc_x, ndc_y, -1.0f, 1.0f);
    const Eigen::Vector4f far_h = inverse_view_projection * Eigen::Vector4f(ndc_x, ndc_y, 1.0f, 1.0f);
    if (near_h.w() == 0.0f || far_h.w() == 0.0f)
        throw InvalidInput("ray_from_ndc: the inverse view-projection maps the point to infinity");
    const Eigen::Vector3f near_p = near_h.head<3>() / near_h.w();
    const Eigen::Vector3f far_p = far_h.head<3>() / far_h.w();
    const Eigen::Vector3f d = far_p - near_p;
    const float len = d.norm();
    if (!(len > 0.0f) || !std::isfinite(len))
        throw InvalidInput("ray_from_ndc: near and far points coincide (singular view-projection)");
    return {near_p, d / len};
}

PickHit pick_particle(const Ray& ray, std::span<const float> x, std::span<const float> y,
                      std::span<const float> z, float radius) {
    const std::size_t n = std::min({x.size(), y.size(), z.size()});
    if (!(radius > 0.0f)) throw InvalidInput("pick radius must be > 0 m");
    const float ox = ray.origin.x(), oy = ray.origin.y(), oz = ray.origin.z();
    const float dx = ray.direction.x(), dy = ray.direction.y(), dz = ray.direction.z();
    const float r2 = radius * radius;
    const std::size_t blocks = (n + pick_block - 1) / pick_block;
    std::vector<PickHit> partial(blocks);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks, 1),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t b = r.begin(); b != r.end(); ++b) {
                              PickHit best;
                              const std::size_t end = std::min(n, (b + 1) * pick_block);
                              for (std::size_t i = b * pick_block; i < end; ++i) {
                                  // |o + t d - c|^2 = r^2 with |d| = 1:  t = tca -+ sqrt(r^2 - d2), tca = (c
                                  // - o).d, d2 = |c - o|^2 - tca^2 the squared distance of the centre from
                                  // the line.
                                  const float cx = x[i] - ox, cy = y[i] - oy, cz = z[i] - oz;
                                  const float tca = cx * dx + cy * dy + cz * dz;
                                  const float d2 = cx * cx + cy * cy + cz * cz - tca * tca;
                                  if (!(d2 <= r2)) continue; // misses the line (or NaN)
                                  const float thc = std::sqrt(r2 - d2);
                                  const float t_exit = tca + thc;
                                  if (t_exit < 0.0f) continue; // the whole sphere lies behind the origin
                                  const float t_enter = std::max(tca - thc, 0.0f);
                                  const PickHit hit{i, t_enter};
                                  if (nearer(hit, best)) best = hit;
                              }
                              partial[b] = best;
                          }
                      });
    PickHit best;
    for (const PickHit& h : partial)
        if (nearer(h, best)) best = h;
    return best;
}

float view_depth(const Eigen::Vector3f& point, const Eigen::Vector3f& eye,
                 const Eigen::Vector3f& forward) noexcept {
    return (point - eye).dot(forward);
}

Eigen::Vector3f point_at_depth(const Ray& ray, const Eigen::Vector3f& eye, const Eigen::Vector3f& forward,
                               float depth) noexcept {
    // Plane: (p - eye) . forward = depth. Ray: p = o + t d  =>  t = (depth - (o - eye) . forward) / (d .
    // forward).
    const float denom = ray.direction.dot(forward);
    const float along = depth - (ray.origin - eye).dot(forward);
    if (std::fabs(denom) < 1e-6f) return ray.origin + along * ray.direction;
    return ray.origin + (along / denom) * ray.direction;
}

} // namespace drape
