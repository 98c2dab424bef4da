// Stage 1 pass (staged pipeline): external accelerations into scratch.
#include "external_forces.hpp"

namespace drape::kernels {

namespace {
template <Integrator I, bool Wind>
void external_forces_impl(const StepContext& c, std::size_t begin, std::size_t end) {
    for (std::size_t p = begin; p < end; p += simd::width) {
        const Vec3b a = external_acceleration<I, Wind>(c, load_self(c, p), movable_lanes(c, p));
        simd::store(c.ax + p, a.x);
        simd::store(c.ay + p, a.y);
        simd::store(c.az + p, a.z);
    }
}
} // namespace

void external_forces_range(const StepContext& c, Integrator integrator, bool wind, std::size_t begin,
                           std::size_t end) {
    if (integrator == Integrator::symplectic_euler)
        wind ? external_forces_impl<Integrator::symplectic_euler, true>(c, begin, end)
             : external_forces_impl<Integrator::symplectic_euler, false>(c, begin, end);
    else
        wind ? external_forces_impl<Integrator::verlet, true>(c, begin, end)
             : external_forces_impl<Integrator::verlet, false>(c, begin, end);
}

} // namespace drape::kernels
