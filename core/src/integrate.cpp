// Stage 3 pass (staged pipeline): integration from scratch forces and accelerations.
#include "integrate.hpp"

namespace drape::kernels {

namespace {
template <Integrator I>
void integrate_impl(const StepContext& c, std::size_t begin, std::size_t end, std::size_t block) {
    fmask ok(true);
    for (std::size_t p = begin; p < end; p += simd::width) {
        const Vec3b f{simd::load(c.fx + p), simd::load(c.fy + p), simd::load(c.fz + p)};
        const Vec3b a{simd::load(c.ax + p), simd::load(c.ay + p), simd::load(c.az + p)};
        ok = ok & integrate_batch<I>(c, p, load_self(c, p), f, a);
    }
    c.block_ok[block] = xsimd::all(ok) ? 1 : 0;
}
} // namespace

void integrate_range(const StepContext& c, Integrator integrator, std::size_t begin, std::size_t end,
                     std::size_t block) {
    integrator == Integrator::symplectic_euler ? integrate_impl<Integrator::symplectic_euler>(c, begin, end, block)
                                               : integrate_impl<Integrator::verlet>(c, begin, end, block);
}

} // namespace drape::kernels
