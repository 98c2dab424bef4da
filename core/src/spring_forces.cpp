// Stage 2 pass (staged pipeline): spring forces into scratch.
#include "spring_forces.hpp"

namespace drape::kernels {

namespace {
template <Integrator I, class Springs>
void spring_forces_impl(const StepContext& c, std::size_t begin, std::size_t end) {
    for (std::size_t p = begin; p < end; p += simd::width) {
        const Vec3b f = Springs::template accumulate<I>(c, p, load_self(c, p));
        simd::store(c.fx + p, f.x);
        simd::store(c.fy + p, f.y);
        simd::store(c.fz + p, f.z);
    }
}
} // namespace

void spring_forces_range(const StepContext& c, Integrator integrator, KernelPath path, std::size_t begin,
                         std::size_t end) {
    const bool grid = path == KernelPath::grid;
    if (integrator == Integrator::symplectic_euler)
        grid ? spring_forces_impl<Integrator::symplectic_euler, GridSprings>(c, begin, end)
             : spring_forces_impl<Integrator::symplectic_euler, CsrSprings>(c, begin, end);
    else
        grid ? spring_forces_impl<Integrator::verlet, GridSprings>(c, begin, end)
             : spring_forces_impl<Integrator::verlet, CsrSprings>(c, begin, end);
}

} // namespace drape::kernels
