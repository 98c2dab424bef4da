// Vertex block descent's local step (Chen et al. 2024, section 3): for one vertex i, the gradient g_i and the
// projected 3x3 Hessian H_i of the implicit step's objective G (implicit.hpp; docs/implicit.md) restricted to x_i,
// then x_i -= H_i^-1 g_i. Scalar, float; the serial and the parallel sweeps call the same function, so they agree bit
// for bit.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include <memory>
#include <span>
#include <type_traits>

#include "drape/aligned_array.hpp"
#include "drape/cloth.hpp"
#include "drape/colliders.hpp"
#include "drape/implicit.hpp"
#include "drape/simd.hpp"

namespace drape::vbd {

/// Cooks the springs, the bending rows and the vertex colouring of a cloth. `twin` (empty, or one entry per particle:
/// its mirror image's index, itself on the mirror plane, UINT32_MAX for none) makes the greedy colouring of a mesh
/// give a particle and its twin the same colour where they are not coupled (mirror_twins below). A mirror-exact
/// cloth (Cloth::mirror not empty) uses its own map instead of `twin`, and the graph is mirror-exact
/// (VbdGraph::mirror_exact: rows in mirror order, exact sums, coupled twins in one colour as declared pairs).
VbdGraph cook(const Cloth& cloth, std::span<const std::uint32_t> twin = {});
/// Each particle's mirror image across the plane x = (min x + max x) / 2 of the positions, where the positions are
/// mirror symmetric: for each particle the particle at its mirrored position (within 1e-5 m; itself on the plane).
/// Empty when under 95 % of the particles have one.
std::vector<std::uint32_t> mirror_twins(std::span<const float> x, std::span<const float> y, std::span<const float> z);
/// Refreshes the springs' k and kd from the cloth's materials (after Simulation::set_material).
void refresh_materials(VbdGraph& graph, const Cloth& cloth);

/// Triangle contact terms inside the sweeps (docs/implicit.md, "Triangle contact inside the solve"): per
/// triangle of the cloth that came within a search reach of a solid collider's inflated surface at the step's
/// start, the barycentric weights b of its deepest point then (a material point q = sum b_j x_j), which
/// collider, a stiffness k (N/m) and that collider's friction mu. The energy k / 2 min(0, phi(q))^2, phi the
/// signed distance of q to the collider's inflated surface, and Coulomb friction on q's tangential move over
/// the step, enter the local step of each of the triangle's vertices (triangle_terms_step).
struct TriangleTerms {
    const std::uint32_t* triangles = nullptr;          ///< 3 particles per triangle
    const std::uint32_t* vertex_tri_offsets = nullptr; ///< CSR: each particle's triangles
    const std::uint32_t* vertex_tris = nullptr;
    const std::uint8_t* vertex_on = nullptr; ///< per particle: one of its triangles has a term
    const std::uint8_t* tri_on = nullptr;    ///< per triangle: 0 no term, else its collider's index + 1
    const float* term = nullptr;             ///< per triangle, triangle_term_floats floats: b0 b1 b2 k mu
    /// The colliders grown by `reach` beyond their thickness: phi(q) = reach - the depth of q in the grown
    /// one (the real inflated surface and the grown one are parallel: both are the solid grown by a ball).
    std::span<const Collider> grown;
    float reach = 0.0f; ///< m
    /// Optional, per triangle: the ellipsoid projection's warm start (ellipsoid_closest_point), read and written by
    /// each corner's step in turn; null: every projection starts cold. Only for colourings in which no colour holds
    /// two corners of a triangle; Solver::run ignores it in the Jacobi sweeps (all vertices at once).
    float* warm = nullptr;
    /// Optional, per triangle (triangle_plane_floats floats): its last projection onto an ellipsoid that found the
    /// contact point inside (surface point, outward unit normal, the contact point it was made from; that point's x
    /// NaN: none). A corner's step whose contact point lies within triangle_plane_reuse R of that point takes the
    /// same tangent plane instead of projecting again, R = min a^2 / max a of the ellipsoid's own semi-axes (its
    /// smallest radius of curvature anywhere; the inflated surface's is larger by about the grown thickness)
    /// (docs/collisions.md, "Tangent planes kept between corners"). Same rules as `warm` (the Jacobi sweeps ignore it
    /// too).
    float* plane = nullptr;
};
inline constexpr std::size_t triangle_term_floats = 5;
inline constexpr std::size_t triangle_plane_floats = 9;
/// The contact point's move (over R, TriangleTerms::plane) within which a kept tangent plane stands in for the
/// surface. For a contact point no deeper than the grown thickness below the inflated surface (whose radii of
/// curvature exceed R by about that thickness) the surface point then moves by at most this times R, the normal turns
/// by at most this (radians) and the depth differs by at most half its square times R (5e-7 R: 5 nm on the T-shirt
/// body's arms, R = 9.2 mm, where the reuse radius is 9.2 um).
inline constexpr float triangle_plane_reuse = 1e-3f;

/// out = H^-1 r for a symmetric 3x3 H (xx yy zz xy xz yz) by its adjugate; false when the determinant is not
/// a positive finite number (out then unchanged).
bool solve_sym3(const float hess[6], const float r[3], float out[3]) noexcept;

/// The local step of vertex i with its triangles' contact terms (TriangleTerms). The free step p minimises
/// the local quadratic model with Hessian hess about x_now (its gradient there is hess (x_now - p)). Each
/// term's constraint phi(q) >= 0 is linearised at x_now (q with vertex i at x_now: phi and the outward normal
/// n there, from the grown collider's projection); a term the free step breaks (phi + b_i n . (p - x_now) <
/// 0) is added to the model (gradient k phi b_i n, Hessian k b_i^2 n n^T) with its friction: the normal force
/// lambda = k max(0, -phi) against q's tangential move u_T since x^n (x0, y0, z0), gradient b_i mu lambda u_T
/// / max(|u_T|, eps), Hessian b_i^2 mu lambda / max(|u_T|, eps) (I - n n^T) (the vertices' own smoothed
/// Coulomb model, eps a slip distance); p becomes that model's minimum. The triangle's other vertices are
/// read from x, y, z at slot[j] (slot null: at j); x0, y0, z0 are indexed by particle. Returns false (p and
/// hess unchanged) when no term is active; else writes p and adds the terms' Hessians to hess. `exact`: a
/// mirror-exact cloth's sums (accumulate<true>; VbdGraph::mirror_exact).
bool triangle_terms_step(const TriangleTerms& terms, std::uint32_t i, const float* x, const float* y,
                         const float* z, const std::uint32_t* slot, const float* x0, const float* y0,
                         const float* z0, float eps, const float x_now[3], float p[3],
                         float hess[6], bool exact = false) noexcept;

/// The arrays one level's sweeps work on (particle_count entries each).
struct LevelState {
    const float* x0; ///< x^n
    const float* y0;
    const float* z0;
    float* x; ///< in: the initial guess; out: the result
    float* y;
    float* z;
    const float* inv_mass; ///< 0 = fixed at x^n
    std::span<const Collider> colliders; ///< kept out of during the sweeps (contact_project)
    /// Optional per-vertex contact planes (self-collision's, docs/self_collision.md "Inside the implicit solve"):
    /// vertex i with a nonzero unit normal n_i stays where n_i . x >= plane_c[i] (projected after its local step,
    /// before the colliders). Null: none.
    const float* plane_nx = nullptr;
    const float* plane_ny = nullptr;
    const float* plane_nz = nullptr;
    const float* plane_c = nullptr;
    /// The guess is the step's inertial prediction (no friction in it yet): its vertices in contact with a collider
    /// lose the Coulomb share of their tangential displacement before the sweeps (Solver::run).
    bool coulomb_guess = false;
    /// A local step that ends inside a solid collider (not a plane) is replaced by its minimum on the contact's
    /// tangent plane (contact_step) rather than projected; never with contact planes (the step along H^-1 n is
    /// tangent to the collider, not to them). The implicit step turns it off with self-collision (the
    /// tangential move it adds is not within the motion the self-collision stage bounds its parts by: the implicit
    /// T-shirt pushed into its back crossed itself in the armpit creases, 4-18 intersecting pairs) and on a cloth
    /// without the multilevel guess (its sweeps end far from the step's minimum, relative residual 0.17 on the tank
    /// top, and with them the tank top on its body blew up at 0.8 s against its 10 % strain limit).
    bool contact_steps = true;
    /// Optional triangle contact terms (TriangleTerms; vertex indices are the cloth's). Null: none.
    const TriangleTerms* triangle_terms = nullptr;
};

/// Contact inside the sweeps: if p is inside a collider (its inflated solid, colliders.hpp), moves it onto the tangent
/// plane of the inflated surface at the point where the segment from p0 (x^n) first enters it (bisection on the
/// segment; p0 inside already: the nearest surface point instead), so a step far longer than a collider is thin
/// never carries a point through it. Returns the collider's friction and writes the unit normal, or returns -1 when p
/// touches no collider. `held` (optional): the last collider it was projected out of.
float contact_project(std::span<const Collider> colliders, const float p0[3], float p[3], float normal[3],
                      const Collider** held = nullptr) noexcept;

/// How far a contact-constrained local step may reach, in multiples of the free step's length plus its depth inside
/// the collider (contact_step's trust region).
inline constexpr float contact_step_reach = 4.0f;

/// The local step constrained to a contact: vertex i at x took the free step to free_step, which ended inside a
/// collider, and contact_project moved it to p on the tangent plane (normal) there. Replaces p with the minimum of the
/// local quadratic model (Hessian hess: xx yy zz xy xz yz; its minimum is free_step) on that plane,
/// free_step + lambda H^-1 n (the KKT point), within a trust region (contact_step_reach). The free step's
/// projection keeps only what the springs' coupling leaves of its tangential part: beside a rim the step that
/// relaxes the spring over the rim goes down, into the collider, and the projection removes it
/// (docs/implicit.md, "The projected local step stalls beside a rim"). Returns false (p unchanged) when p is not
/// behind the plane or the model is degenerate.
bool contact_step(const float hess[6], const float x[3], const float free_step[3], float p[3],
                  const float normal[3]) noexcept;

struct VbdSlices;
class GridLayout;

/// The sweeps of one cloth (one level of the multilevel solve, or the only one): its cooked graph and scratch.
class Solver {
  public:
    Solver();
    ~Solver();
    Solver(Solver&&) noexcept;
    Solver& operator=(Solver&&) noexcept;
    void cook(const Cloth& cloth, std::span<const std::uint32_t> twin = {});
    /// Refreshes the springs' k and kd from the cloth's materials (after Simulation::set_material).
    void refresh_materials(const Cloth& cloth);
    /// Sets every spring's rest length from `edge_rest` (per Cloth::edges entry; seams being sewn change theirs).
    void set_spring_rest(std::span<const float> edge_rest);
    /// Gauss-Seidel sweeps run simd::width vertices of a colour at once (vbd_batch.hpp; default) or one by one with
    /// solve_vertex (the scalar reference; the same bits).
    void set_simd(bool on) noexcept { simd_ = on; }
    /// A grid cloth's Gauss-Seidel sweeps run on its colour sub-grids (vbd_grid.hpp: contiguous loads, no gathers;
    /// default where the cloth fits the layout) or on the gathered slices (off; the same bits).
    void set_grid(bool on) noexcept { grid_on_ = on; }
    /// Whether the Gauss-Seidel sweeps run on the grid layout.
    bool grid_sweeps() const noexcept { return grid_ != nullptr && grid_on_ && simd_; }
    bool cooked() const noexcept { return !graph_.colour_offsets.empty(); }
    VbdGraph& graph() noexcept { return graph_; }
    const VbdGraph& graph() const noexcept { return graph_; }
    /// The inertial prediction y, to fill before run() (particle_count entries each).
    float* pred_x() noexcept { return pred_x_.data(); }
    float* pred_y() noexcept { return pred_y_.data(); }
    float* pred_z() noexcept { return pred_z_.data(); }
    /// Per vertex after run(): the unit normal of the contact that held it in the last sweep (0 0 0: none).
    const float* contact_nx() const noexcept { return contact_nx_.data(); }
    const float* contact_ny() const noexcept { return contact_ny_.data(); }
    const float* contact_nz() const noexcept { return contact_nz_.data(); }
    /// Runs the sweeps of one step of length h with air drag kr (1/s). No allocation.
    template <bool Parallel>
    ImplicitStats run(const LevelState& s, const ImplicitParams& params, float h, float air_drag);
    /// Where gradient() evaluates: the iterate x (read only) and x^n, and which vertices are fixed.
    struct Point {
        const float* x0; ///< x^n
        const float* y0;
        const float* z0;
        const float* x; ///< the iterate
        const float* y;
        const float* z;
        const float* inv_mass; ///< 0 = fixed
    };
    /// The gradient of the step's objective G at p.x (N per vertex; 0 at fixed vertices), on the prediction filled
    /// in; no step taken. No allocation. SIMD on the slices (set_simd, default) or solve_vertex<true> vertex by
    /// vertex: the same bits.
    template <bool Parallel>
    void gradient(const Point& p, float h, float air_drag, float* gx, float* gy, float* gz) const;

  private:
    VbdGraph graph_;
    std::vector<float> pred_x_, pred_y_, pred_z_, cheb1_x_, cheb1_y_, cheb1_z_, cheb2_x_, cheb2_y_, cheb2_z_;
    std::vector<float> jac_x_, jac_y_, jac_z_;
    std::vector<float> contact_nx_, contact_ny_, contact_nz_;
    AlignedArray<float> fr_nx_, fr_ny_, fr_nz_, fr_k_; ///< SweepArgs' friction, in the iterate's order
    std::vector<double> chunk_residual_;          ///< per fixed chunk of a sweep: sum of |g_i|^2
    std::vector<std::uint32_t> colour_chunk_base_; ///< per colour: its first chunk in chunk_residual_
    std::unique_ptr<VbdSlices> slices_;
    std::unique_ptr<GridLayout> grid_;
    bool simd_ = true, grid_on_ = true;
};

/// Everything one sweep reads: the state at the start of the step, the inertial prediction, the iterate.
struct SweepArgs {
    const float* __restrict x0; ///< x^n
    const float* __restrict y0;
    const float* __restrict z0;
    const float* __restrict px; ///< inertial prediction y = x^n + h v^n + h^2 a (minus f_ext h^2 / m folded in)
    const float* __restrict py;
    const float* __restrict pz;
    const float* x; ///< the iterate (read; Gauss-Seidel writes it in place, Jacobi into out_*)
    const float* y;
    const float* z;
    const float* __restrict inv_mass;
    const VbdGraph* graph;
    float inv_h2;      ///< 1 / h^2
    float drag_over_h; ///< kr / h
    float inv_h;       ///< 1 / h
    /// Coulomb friction against the colliders (docs/collisions.md, "Friction inside the sweeps"), per vertex in the
    /// iterate's order (particles; cells on a grid layout): the unit normal of its contact and the bound mu |f_n| (N)
    /// of its friction force, lagged (from the step's initial guess, then each sweep's contact). Null: no friction.
    /// It adds the smoothed Coulomb potential D = fr_k f0(|u|), u = (I - n n^T)(x_i - x_i^n), to the vertex's local
    /// objective, as a quadratic majorizer at the iterate: gradient w u, Hessian w (I - n n^T), w = fr_k f1(|u|) / |u|
    /// (f1(s) = 1 beyond fr_eps, s / fr_eps (2 - s / fr_eps) below: IPC's smoothing of the stick-slip switch).
    const float* fr_nx = nullptr;
    const float* fr_ny = nullptr;
    const float* fr_nz = nullptr;
    const float* fr_k = nullptr;
    float fr_eps = 0.0f; ///< slip (m) below which friction is smoothed: friction_slip_speed h
};

/// The sliding speed (m/s) below which the implicit solver's friction is smoothed (IPC's eps_v; Li et al. 2020 use
/// 1e-3 m/s): a vertex pushed along a surface by less than its friction bound creeps at most about this fast.
inline constexpr float friction_slip_speed = 1e-3f;

/// The friction weight w = fr_k f1(s) / s of SweepArgs for a tangential slip s (one definition for the scalar and
/// the SIMD sweeps: T = float or simd::fbatch, the same operations).
template <class T> inline T friction_weight(T k, T s, T eps) noexcept {
    const T one(1.0f), two(2.0f);
    if constexpr (std::is_same_v<T, float>) {
        return k * (s >= eps ? one / s : (two - s / eps) / eps);
    } else {
        const auto slipping = s >= eps;
        return k * simd::select(slipping, one / simd::select(slipping, s, one), (two - s / eps) / eps);
    }
}

/// Halvings of a local step before it is dropped. The local Hessian of a flat, unstretched cloth has no stiffness
/// across it (its springs lie in its plane) while the energy grows like the fourth power of an out-of-plane move, so a
/// light, stiff cloth's first steps need many halvings: with 8 a 1 g, 1 cm, 1000 N/m cloth hanging from two corners
/// (scenes/examples/far_from_origin.json) dropped every step at h = 1/30 s and never moved.
inline constexpr int vbd_line_search_halvings = 20;

/// acc + a * b: fused (one rounding), or Exact: the product rounded, then the sum (a mirror-exact cloth,
/// VbdGraph::mirror_exact). A particle on the mirror plane adds each term next to its mirror image's, whose x part is
/// the negation: with the product rounded apart the pair cancels exactly, fused it leaves the product's rounding error
/// (the explicit kernels' accumulate_term, spring_forces.hpp, for the same reason). T = float or simd::fbatch.
template <bool Exact, class T> inline T accumulate(T a, T b, T acc) noexcept {
    if constexpr (Exact) return acc + a * b;
    else return simd::fma(a, b, acc);
}
/// acc - a * b, as accumulate.
template <bool Exact, class T> inline T accumulate_neg(T a, T b, T acc) noexcept {
    if constexpr (Exact) return acc - a * b;
    else if constexpr (std::is_same_v<T, float>) return std::fma(-a, b, acc);
    else return simd::fnma(a, b, acc);
}

/// Spring damping's Hessian blocks q n n^T summed from zero, for one vertex (T = float: solve_vertex) or one per lane
/// (T = simd::fbatch: vbd_batch.hpp's solve_lanes, and a grid cloth's per-step cook, GridLayout::cook_damping): one
/// definition, so the scalar reference and the SIMD sweeps do the same operations in the same order.
template <class T> struct DampingHessian {
    T xx = T(0.0f), yy = xx, zz = xx, xy = xx, xz = xx, yz = xx;
    template <bool Exact = false> void add(T q, T nx, T ny, T nz) noexcept {
        const T qx = q * nx, qy = q * ny;
        xx = simd::fma(qx, nx, xx);
        yy = simd::fma(qy, ny, yy);
        zz = simd::fma(q * nz, nz, zz);
        xy = accumulate<Exact>(qx, ny, xy);
        xz = accumulate<Exact>(qx, nz, xz);
        yz = simd::fma(qy, nz, yz);
    }
};

/// Adds a I + b u u^T to a symmetric 3x3 block (xx yy zz xy xz yz): a spring's projected Hessian (a = c, b = k - c)
/// and friction's w (I - n n^T) (a = w, b = -w). T = float (solve_vertex) or simd::fbatch (solve_lanes): one
/// definition, so the scalar reference and the SIMD sweeps do the same operations in the same order. Exact:
/// the entries a mirror negates (xy, xz) summed as accumulate<true>.
template <bool Exact = false, class T>
inline void add_isotropic_outer(T a, T b, T ux, T uy, T uz, T& xx, T& yy, T& zz, T& xy, T& xz, T& yz) noexcept {
    const T tx = b * ux, ty = b * uy;
    xx = xx + simd::fma(tx, ux, a);
    yy = yy + simd::fma(ty, uy, a);
    zz = zz + simd::fma(b * uz, uz, a);
    xy = accumulate<Exact>(tx, uy, xy);
    xz = accumulate<Exact>(tx, uz, xz);
    yz = simd::fma(ty, uz, yz);
}

/// Writes a local Hessian's six entries (xx yy zz xy xz yz) to `out` (T = float: solve_vertex; simd::fbatch:
/// solve_lanes), for the constrained contact step (contact_step).
template <class T> inline void write_hessian(T* out, T xx, T yy, T zz, T xy, T xz, T yz) noexcept {
    out[0] = xx;
    out[1] = yy;
    out[2] = zz;
    out[3] = xy;
    out[4] = xz;
    out[5] = yz;
}

/// The local Newton step of vertex i (movable): writes the new position and returns |g_i|^2 (N^2). GradientOnly:
/// writes g_i (the gradient of G at the iterate, N) instead and takes no step. `hess` (optional): the local Hessian
/// H_i the step solved with (xx yy zz xy xz yz), for a step constrained to a contact afterwards (Solver::run).
template <bool GradientOnly = false, bool Exact = false>
inline float solve_vertex(const SweepArgs& a, std::uint32_t i, float out[3], float* hess = nullptr) noexcept {
    const VbdGraph& g = *a.graph;
    const float xi = a.x[i], yi = a.y[i], zi = a.z[i];
    const float dxi = xi - a.x0[i], dyi = yi - a.y0[i], dzi = zi - a.z0[i]; // this step's displacement
    const float m = 1.0f / a.inv_mass[i];
    // Inertia and air drag: m/h^2 (x - y) + m kr/h (x - x^n).
    const float mi = m * a.inv_h2, md = m * a.drag_over_h;
    float gx = std::fma(mi, xi - a.px[i], md * dxi);
    float gy = std::fma(mi, yi - a.py[i], md * dyi);
    float gz = std::fma(mi, zi - a.pz[i], md * dzi);
    const float base = mi + md;
    float hxx = base, hyy = hxx, hzz = hxx, hxy = 0.0f, hxz = 0.0f, hyz = 0.0f;
    // The terms quadratic in x_i (inertia, drag, damping, bending) are tracked apart from the springs' stretch:
    // G restricted to x_i is then exactly qg . d + 1/2 d^T QH d + sum of the springs' stretch energies, which the
    // line search below evaluates. qh_* hold the quadratic terms' Hessian; dh_* the springs' damping part of it,
    // summed from zero (DampingHessian; the SIMD grid sweeps read it cooked once per step: vbd_batch.hpp damping_q).
    DampingHessian<float> dh;
    float sgx = 0.0f, sgy = 0.0f, sgz = 0.0f; // the springs' stretch gradient
    // Springs: E = k/2 (L - l)^2, grad_i = -k (L - l) u (u from i to j); projected Hessian k (c I + (1 - c) u u^T),
    // c = max(0, 1 - l/L). Damping along n, the direction at the start of the step: grad_i = -(kd/h) (dd . n) n,
    // dd = (x_j - x_j^n) - (x_i - x_i^n) = d - n; Hessian (kd/h) n n^T.
    // Written without branches and with fused multiply-adds, operation for operation as the SIMD kernel
    // (vbd_batch.hpp solve_lanes), so that both give the same bits: a term that does not apply has a zero factor.
    for (std::uint32_t e = g.spring_offsets[i], end = g.spring_offsets[i + 1]; e < end; ++e) {
        const std::uint32_t j = g.spring_neighbour[e];
        const float k = g.spring_k[e], l = g.spring_rest[e];
        const float dx = a.x[j] - xi, dy = a.y[j] - yi, dz = a.z[j] - zi;
        const float len2 = std::fma(dz, dz, std::fma(dy, dy, dx * dx));
        const bool stretched = len2 > 1e-24f;
        const float inv_len = simd::rsqrt(stretched ? len2 : 1.0f); // as the SIMD kernel: no division
        const float l0 = len2 * inv_len;
        const float ux = dx * inv_len, uy = dy * inv_len, uz = dz * inv_len;
        const float s = stretched ? k * (l0 - l) : 0.0f;
        sgx = accumulate_neg<Exact>(s, ux, sgx);
        sgy = accumulate_neg<Exact>(s, uy, sgy);
        sgz = accumulate_neg<Exact>(s, uz, sgz);
        const float c = k * std::max(0.0f, std::fma(-l, inv_len, 1.0f));
        // A zero-length spring at its rest: E = k/2 |d|^2, Hessian k I.
        const float cm = stretched ? c : (l == 0.0f ? k : 0.0f), cu = stretched ? k - c : 0.0f;
        add_isotropic_outer<Exact>(cm, cu, ux, uy, uz, hxx, hyy, hzz, hxy, hxz, hyz);
        const float kd = g.spring_kd[e] * a.inv_h;
        const float nx = a.x0[j] - a.x0[i], ny = a.y0[j] - a.y0[i], nz = a.z0[j] - a.z0[i];
        const float n2 = std::fma(nz, nz, std::fma(ny, ny, nx * nx));
        const bool damped = kd > 0.0f && n2 > 1e-24f;
        const float q = damped ? kd / n2 : 0.0f; // kd / |n|^2
        dh.template add<Exact>(q, nx, ny, nz);
        const float p = q * std::fma(dz - nz, nz, std::fma(dy - ny, ny, (dx - nx) * nx));
        gx = accumulate_neg<Exact>(p, nx, gx);
        gy = accumulate_neg<Exact>(p, ny, gy);
        gz = accumulate_neg<Exact>(p, nz, gz);
    }
    float qhxx = base + dh.xx, qhyy = base + dh.yy, qhzz = base + dh.zz, qhxy = dh.xy, qhxz = dh.xz, qhyz = dh.yz;
    // Bending: grad_i = sum_j Q_ij [(x_j - x_i) + beta/h ((x_j - x_j^n) - (x_i - x_i^n))] (rows of Q sum to 0),
    // Hessian Q_ii (1 + beta/h) I.
    if (!g.bend_diag.empty()) {
        const float bh = g.bend_beta * a.inv_h;
        float bx = 0.0f, by = 0.0f, bz = 0.0f;
        for (std::uint32_t e = g.bend_offsets[i], end = g.bend_offsets[i + 1]; e < end; ++e) {
            const std::uint32_t j = g.bend_neighbour[e];
            const float q = g.bend_q[e];
            bx = accumulate<Exact>(q, std::fma(bh, (a.x[j] - a.x0[j]) - dxi, a.x[j] - xi), bx);
            by = accumulate<Exact>(q, std::fma(bh, (a.y[j] - a.y0[j]) - dyi, a.y[j] - yi), by);
            bz = accumulate<Exact>(q, std::fma(bh, (a.z[j] - a.z0[j]) - dzi, a.z[j] - zi), bz);
        }
        gx += bx;
        gy += by;
        gz += bz;
        const float d = g.bend_diag[i] * (1.0f + bh);
        qhxx += d;
        qhyy += d;
        qhzz += d;
    }
    // Friction (SweepArgs::fr_k): a quadratic term at the iterate, gradient w u, Hessian w (I - n n^T).
    if (a.fr_k != nullptr) {
        const float nx = a.fr_nx[i], ny = a.fr_ny[i], nz = a.fr_nz[i];
        const float dn = std::fma(dzi, nz, std::fma(dyi, ny, dxi * nx));
        const float ux = std::fma(-dn, nx, dxi), uy = std::fma(-dn, ny, dyi), uz = std::fma(-dn, nz, dzi);
        const float s = std::sqrt(std::fma(uz, uz, std::fma(uy, uy, ux * ux)));
        const float w = friction_weight(a.fr_k[i], s, a.fr_eps);
        gx = accumulate<Exact>(w, ux, gx);
        gy = accumulate<Exact>(w, uy, gy);
        gz = accumulate<Exact>(w, uz, gz);
        add_isotropic_outer<Exact>(w, -w, nx, ny, nz, qhxx, qhyy, qhzz, qhxy, qhxz, qhyz);
    }
    // Total: quadratic terms plus the springs' stretch (hxx.. so far hold inertia + the springs' projected Hessian).
    hxx += qhxx - base;
    hyy += qhyy - base;
    hzz += qhzz - base;
    hxy += qhxy;
    hxz += qhxz;
    hyz += qhyz;
    const float qgx = gx, qgy = gy, qgz = gz; // gradient of the quadratic terms
    gx += sgx;
    gy += sgy;
    gz += sgz;
    if constexpr (GradientOnly) {
        out[0] = gx;
        out[1] = gy;
        out[2] = gz;
        return gx * gx + gy * gy + gz * gz;
    }
    if (hess != nullptr) write_hessian(hess, hxx, hyy, hzz, hxy, hxz, hyz);
    // x_i -= H^-1 g by the adjugate (H is symmetric positive definite: the inertia term alone is m/h^2 I).
    const float c00 = hyy * hzz - hyz * hyz, c01 = hxz * hyz - hxy * hzz, c02 = hxy * hyz - hxz * hyy;
    const float c11 = hxx * hzz - hxz * hxz, c12 = hxy * hxz - hxx * hyz, c22 = hxx * hyy - hxy * hxy;
    const float det = hxx * c00 + hxy * c01 + hxz * c02;
    const float inv_det = 1.0f / det;
    float ddx = -(c00 * gx + c01 * gy + c02 * gz) * inv_det;
    float ddy = -(c01 * gx + c11 * gy + c12 * gz) * inv_det;
    float ddz = -(c02 * gx + c12 * gy + c22 * gz) * inv_det;
    // Backtracking line search on the local objective (the projected Hessian makes the step a descent direction,
    // but a vertex between nearly parallel springs can overshoot far): halve the step until G does not rise.
    // As differences, so the change keeps its digits close to convergence (where it is far below float's resolution
    // of G itself): a spring's stretch energy changes by k/2 (L1 - L0) (L1 + L0 - 2 l), and L1 - L0 =
    // (|p|^2 - 2 d . p) / (L1 + L0) for a move p of vertex i (d = x_j - x_i) has no cancellation.
    auto change = [&](float px, float py, float pz) {
        float e = qgx * px + qgy * py + qgz * pz +
                  0.5f * (qhxx * px * px + qhyy * py * py + qhzz * pz * pz) + qhxy * px * py + qhxz * px * pz +
                  qhyz * py * pz;
        const float p2 = px * px + py * py + pz * pz;
        for (std::uint32_t s = g.spring_offsets[i], end = g.spring_offsets[i + 1]; s < end; ++s) {
            const std::uint32_t j = g.spring_neighbour[s];
            const float dx = a.x[j] - xi, dy = a.y[j] - yi, dz = a.z[j] - zi;
            const float len2 = std::fma(dz, dz, std::fma(dy, dy, dx * dx));
            const float l0 = len2 * simd::rsqrt(len2 > 1e-24f ? len2 : 1.0f);
            const float ex = dx - px, ey = dy - py, ez = dz - pz;
            const float l1 = std::sqrt(std::fma(ez, ez, std::fma(ey, ey, ex * ex)));
            const float sum = l0 + l1;
            if (!(sum > 0.0f)) continue;
            const float dl = std::fma(-2.0f, std::fma(dz, pz, std::fma(dy, py, dx * px)), p2) / sum;
            e += 0.5f * g.spring_k[s] * dl * std::fma(-2.0f, g.spring_rest[s], sum);
        }
        return e;
    };
    // A step that is not finite (a singular Hessian in float: found with stretch 1e6 N/m across 10 N/m and shear
    // 0.01) is no step; a change that is not finite counts as a rise (NaN > 0 is false: it was taken).
    const float sum_dd = ddx + ddy + ddz;
    if (!(sum_dd - sum_dd == 0.0f)) ddx = ddy = ddz = 0.0f;
    for (int halving = 0; halving < vbd_line_search_halvings && !(change(ddx, ddy, ddz) <= 0.0f); ++halving) {
        ddx *= 0.5f;
        ddy *= 0.5f;
        ddz *= 0.5f;
        if (halving == vbd_line_search_halvings - 1) ddx = ddy = ddz = 0.0f;
    }
    out[0] = xi + ddx;
    out[1] = yi + ddy;
    out[2] = zi + ddz;
    return gx * gx + gy * gy + gz * gz;
}

} // namespace drape::vbd
