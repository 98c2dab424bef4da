// Stage 2 pass (staged pipeline): spring forces into scratch.
#include "spring_forces.hpp"

namespace drape::kernels {

namespace {
template <Integrator I, class Springs, bool Extra>
void spring_forces_impl(const StepContext& c, std::size_t begin, std::size_t end) {
    for (std::size_t p = begin; p < end; p += simd::width) {
        Vec3b f = Springs::template accumulate<I>(c, p, load_self(c, p));
        add_extra_forces<Extra>(c, p, f);
        simd::store(c.fx + p, f.x);
        simd::store(c.fy + p, f.y);
        simd::store(c.fz + p, f.z);
    }
}
} // namespace

template <bool Extra>
void spring_forces_dispatch(const StepContext& c, Integrator integrator, KernelPath path, std::size_t begin,
                            std::size_t end) {
    const bool grid = path == KernelPath::grid;
    if (integrator == Integrator::symplectic_euler)
        grid ? spring_forces_impl<Integrator::symplectic_euler, GridSprings, Extra>(c, begin, end)
             : spring_forces_impl<Integrator::symplectic_euler, CsrSprings, Extra>(c, begin, end);
    else
        grid ? spring_forces_impl<Integrator::verlet, GridSprings, Extra>(c, begin, end)
             : spring_forces_impl<Integrator::verlet, CsrSprings, Extra>(c, begin, end);
}

void spring_forces_range(const StepContext& c, Integrator integrator, KernelPath path, bool seams, std::size_t begin,
                         std::size_t end) {
    seams ? spring_forces_dispatch<true>(c, integrator, path, begin, end)
          : spring_forces_dispatch<false>(c, integrator, path, begin, end);
}

} // namespace drape::kernels
