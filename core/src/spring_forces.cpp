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

template <Integrator I, bool Extra>
void spring_forces_dispatch(const StepContext& c, KernelPath path, std::size_t begin, std::size_t end) {
    if (path == KernelPath::grid)
        c.bending ? spring_forces_impl<I, GridFabric, Extra>(c, begin, end)
                  : spring_forces_impl<I, GridSprings, Extra>(c, begin, end);
    else if (c.mirror)
        c.bending ? spring_forces_impl<I, CsrFabricT<true>, Extra>(c, begin, end)
                  : spring_forces_impl<I, CsrSpringsT<true>, Extra>(c, begin, end);
    else
        c.bending ? spring_forces_impl<I, CsrFabric, Extra>(c, begin, end)
                  : spring_forces_impl<I, CsrSprings, Extra>(c, begin, end);
}

template <bool Extra>
void spring_forces_dispatch(const StepContext& c, Integrator integrator, KernelPath path, std::size_t begin,
                            std::size_t end) {
    integrator == Integrator::symplectic_euler
        ? spring_forces_dispatch<Integrator::symplectic_euler, Extra>(c, path, begin, end)
        : spring_forces_dispatch<Integrator::verlet, Extra>(c, path, begin, end);
}

void spring_forces_range(const StepContext& c, Integrator integrator, KernelPath path, bool seams, std::size_t begin,
                         std::size_t end) {
    seams ? spring_forces_dispatch<true>(c, integrator, path, begin, end)
          : spring_forces_dispatch<false>(c, integrator, path, begin, end);
}

} // namespace drape::kernels
