// Vertex block descent on a grid cloth without gathers: the vertices are rearranged by colour into sub-grids, so the
// simd::width vertices of a colour that one batch solves sit side by side, and so do each of their neighbours in any
// one direction. The sweeps then load everything contiguously (vbd_batch.hpp's solve_lanes with GridSource below),
// with the same operations in the same order as the scalar solve_vertex: the same bits (tests/test_implicit.cpp).
//
// Layout. A grid cloth (index = row * columns + column) whose springs and bending rows reach at most two rows and two
// columns, and whose greedy colouring (vbd.cpp) is the pattern (row mod P, column mod P) with P = 2 or 3, has P^2
// classes (a, b). Class (a, b) holds the vertices (a + P p, b + P q) at sub-grid row p and column q. The neighbour of
// (a + P p, b + P q) at (dr, dc) is in class ((a + dr) mod P, (b + dc) mod P) at (p + floor((a + dr) / P),
// q + floor((b + dc) / P)), a shift of -1, 0 or +1: one constant index offset per class and direction ("delta").
// Memory holds each class's sub-grid by itself, row-major with a stride of sub_columns + 1: the one extra column is
// the zero halo on both sides of a row (column -1 of row p is column sub_columns of row p - 1), and a halo row lies
// above and below. A class's first cell is simd::width-aligned and its batches run through its cells as one
// sequence, across row ends, so the lanes wasted on halo are one per row (before 2026-11-28 every row was padded to
// whole batches with 16 halo columns: 68 % of the lanes of N = 100's finest level did work, 11 % of its 7 x 7 level;
// now 93 % and 34 %; docs/implicit.md, "Sub-grids without row padding"). Cells outside the cloth hold zero mass (never
// written) and zero coefficients (they add exactly nothing); a halo lane's neighbour loads land on finite cells of the
// allocation and its results are dropped.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "drape/aligned_array.hpp"
#include "drape/simd.hpp"
#include "vbd.hpp"
#include "vbd_batch.hpp"

namespace drape::vbd {

class GridLayout {
  public:
    /// The layout of a grid cloth of rows x columns particles with this cooked graph, or null when the cloth does not
    /// fit it (a spring or bending entry further than two rows or columns, a row out of direction order, a colouring
    /// that is not the pattern): the sweeps then run on the gathered slices.
    static std::unique_ptr<GridLayout> cook(const VbdGraph& graph, std::uint32_t rows, std::uint32_t columns);
    /// Copies every spring's k, kd and rest length and the bending rows from the graph (after a material change).
    void refresh(const VbdGraph& graph);
    /// Copies only the springs' rest lengths (Solver::set_spring_rest: seams being sewn, FAS's slack coarse
    /// springs); the slots stay where refresh put them.
    void refresh_rest(const VbdGraph& graph);

    std::size_t cells() const noexcept { return cells_; }
    std::size_t colour_count() const noexcept { return colour_class_.size(); }
    std::size_t chunks_per_colour() const noexcept { return chunks_; }
    /// The cell of particle i.
    std::size_t cell_of(std::size_t i) const noexcept { return cell_of_[i]; }
    const std::uint32_t* cell_of_data() const noexcept { return cell_of_.data(); }
    std::size_t spring_slots() const noexcept { return spring_dir_.size(); }
    std::size_t bend_slots() const noexcept { return bend_dir_.size(); }
    std::uint32_t period() const noexcept { return period_; }

    /// Copies a level's arrays (particle order) into the packed state: iterate, x^n, prediction, inverse mass.
    template <bool Parallel>
    void pack(const LevelState& s, const float* px, const float* py, const float* pz);
    /// Copies the packed iterate back into s.x, s.y, s.z.
    template <bool Parallel> void unpack(const LevelState& s) const;

    /// Cooks the springs' damping of this step (vbd_batch.hpp damping_q, DampingHessian) from the packed x^n, after
    /// pack: it depends only on the state at the start of the step, so the sweeps read it instead of recomputing it.
    template <bool Parallel> void cook_damping(const SweepArgs& packed);

    /// The sweep arguments over the packed state (the rest of `a` kept).
    SweepArgs packed_args(SweepArgs a) noexcept;
    float* x() noexcept { return x_.data(); }
    float* y() noexcept { return y_.data(); }
    float* z() noexcept { return z_.data(); }
    const float* inv_mass() const noexcept { return inv_mass_.data(); }

    /// Solves chunk `chunk` of colour `colour` (a fixed run of batches, so the chunks' residuals are the same for any
    /// thread count): each movable vertex's new position goes into the packed iterate, through `keep_out`
    /// when there are colliders (keep_out(particle, cell, float[3], the local Hessian's 6 entries)). Returns the chunk's sum of |g|^2 in lane order.
    template <class KeepOut>
    double solve_chunk(const SweepArgs& packed, std::size_t colour, std::size_t chunk, bool contact,
                       KeepOut&& keep_out) noexcept;

  private:
    friend struct GridSource;
    /// Sub-grid row p (-1 ... sub_rows) and column q (-1 ... sub_columns) of class cls; row -1 and column -1 index
    /// backwards from the class's first cell.
    std::size_t cell(std::uint32_t cls, std::int32_t p, std::int32_t q) const noexcept {
        return std::size_t(std::ptrdiff_t(class_base(cls)) + std::ptrdiff_t(p) * stride_ + q);
    }
    std::size_t class_base(std::uint32_t cls) const noexcept { return front_ + std::size_t(cls) * region_; }
    /// The class a * P + b of particle i (row i / columns, column i % columns).
    std::size_t class_of(std::size_t i) const noexcept {
        return (i / columns_ % period_) * period_ + i % columns_ % period_;
    }
    /// Coefficients are stored batch by batch: the simd::width cells of a batch, slot after slot, so that one batch
    /// reads one contiguous block (one memory stream, not one per slot).
    std::size_t spring_at(std::size_t cell, std::size_t slot) const noexcept {
        return (cell - cell % simd::width) * spring_dir_.size() + slot * simd::width + cell % simd::width;
    }
    std::size_t bend_at(std::size_t cell, std::size_t slot) const noexcept {
        return (cell - cell % simd::width) * bend_dir_.size() + slot * simd::width + cell % simd::width;
    }

    std::uint32_t period_ = 0, columns_ = 0;
    std::uint32_t stride_ = 0; ///< a class's sub-grid row: its columns + 1 halo column
    std::size_t front_ = 0;  ///< cells before class 0's first cell (its halo, and halo lanes' loads)
    std::size_t region_ = 0; ///< cells from one class's first cell to the next one's (a multiple of simd::width)
    std::size_t cells_ = 0, batches_ = 0, batches_per_chunk_ = 1, chunks_ = 0, particles_ = 0;
    std::vector<std::array<std::int32_t, 2>> spring_dir_, bend_dir_; ///< slot -> (dr, dc), ascending
    std::vector<std::uint32_t> cell_of_;           ///< per particle: its cell
    AlignedArray<std::uint32_t> particle_;         ///< per cell: its particle (UINT32_MAX outside the cloth)
    std::vector<std::uint32_t> colour_class_;      ///< per colour (sweep order): its class a * P + b
    std::vector<std::int32_t> spring_delta_, bend_delta_; ///< per class x slot: neighbour cell - own cell
    AlignedArray<float> k_, kd_, rest_, q_;        ///< per cell x slot (spring_at, bend_at)
    AlignedArray<float> diag_;                     ///< per cell: Q_ii
    AlignedArray<float> dq_;                       ///< per cell x slot (spring_at): this step's damping_q
    AlignedArray<float> dh_[6];                    ///< per cell: this step's DampingHessian (xx yy zz xy xz yz)
    AlignedArray<float> x_, y_, z_, x0_, y0_, z0_, px_, py_, pz_, inv_mass_; ///< packed state, per cell
};

/// The batch of simd::width cells starting at `o` (solve_lanes's source): own values and neighbours by contiguous
/// loads at the class's constant offsets.
struct GridSource {
    static constexpr bool cooked_damping = true;
    const GridLayout& g;
    std::size_t o;
    const std::int32_t* sd; ///< this class's spring deltas
    const std::int32_t* bd; ///< this class's bending deltas
    simd::fbatch own(const float* f) const noexcept { return simd::load(f + o); }
    std::size_t springs() const noexcept { return g.spring_dir_.size(); }
    std::size_t bends() const noexcept { return g.bend_dir_.size(); }
    simd::fbatch spring_k(std::size_t s) const noexcept { return simd::load(g.k_.data() + g.spring_at(o, s)); }
    simd::fbatch spring_kd(std::size_t s) const noexcept { return simd::load(g.kd_.data() + g.spring_at(o, s)); }
    simd::fbatch spring_rest(std::size_t s) const noexcept { return simd::load(g.rest_.data() + g.spring_at(o, s)); }
    void spring_pos(std::size_t s, const float* x, const float* y, const float* z, simd::fbatch& ox, simd::fbatch& oy,
                    simd::fbatch& oz) const noexcept {
        load3(std::ptrdiff_t(o) + sd[s], x, y, z, ox, oy, oz);
    }
    simd::fbatch damping_q(std::size_t s) const noexcept { return simd::load(g.dq_.data() + g.spring_at(o, s)); }
    DampingHessian<simd::fbatch> damping_hessian() const noexcept {
        DampingHessian<simd::fbatch> h;
        h.xx = simd::load(g.dh_[0].data() + o);
        h.yy = simd::load(g.dh_[1].data() + o);
        h.zz = simd::load(g.dh_[2].data() + o);
        h.xy = simd::load(g.dh_[3].data() + o);
        h.xz = simd::load(g.dh_[4].data() + o);
        h.yz = simd::load(g.dh_[5].data() + o);
        return h;
    }
    simd::fbatch bend_q(std::size_t s) const noexcept { return simd::load(g.q_.data() + g.bend_at(o, s)); }
    void bend_pos(std::size_t s, const float* x, const float* y, const float* z, simd::fbatch& ox, simd::fbatch& oy,
                  simd::fbatch& oz) const noexcept {
        load3(std::ptrdiff_t(o) + bd[s], x, y, z, ox, oy, oz);
    }
    simd::fbatch bend_diag() const noexcept { return simd::load(g.diag_.data() + o); }
    static void load3(std::ptrdiff_t at, const float* x, const float* y, const float* z, simd::fbatch& ox,
                      simd::fbatch& oy, simd::fbatch& oz) noexcept {
        ox = simd::loadu(x + at);
        oy = simd::loadu(y + at);
        oz = simd::loadu(z + at);
    }
};

template <class KeepOut>
double GridLayout::solve_chunk(const SweepArgs& a, std::size_t colour, std::size_t chunk, bool contact,
                               KeepOut&& keep_out) noexcept {
    constexpr std::size_t W = simd::width;
    const std::uint32_t cls = colour_class_[colour];
    const std::int32_t* sd = spring_delta_.data() + std::size_t(cls) * spring_dir_.size();
    const std::int32_t* bd = bend_delta_.data() + std::size_t(cls) * bend_dir_.size();
    const std::size_t b0 = chunk * batches_per_chunk_, b1 = std::min(batches_, b0 + batches_per_chunk_);
    double r = 0.0;
    alignas(64) float g2[W];
    for (std::size_t b = b0; b < b1; ++b) {
        const std::size_t o = class_base(cls) + b * W;
        simd::fbatch ox, oy, oz, og, h[6];
        solve_lanes(GridSource{*this, o, sd, bd}, a, ox, oy, oz, og, contact ? h : nullptr);
        simd::store(g2, og);
        const simd::fbatch w = simd::load(inv_mass_.data() + o);
        for (std::size_t lane = 0; lane < W; ++lane)
            if (inv_mass_[o + lane] != 0.0f) r += g2[lane];
        if (!contact) {
            const simd::fmask movable = w != simd::fbatch(0.0f);
            simd::store(x_.data() + o, simd::select(movable, ox, simd::load(x_.data() + o)));
            simd::store(y_.data() + o, simd::select(movable, oy, simd::load(y_.data() + o)));
            simd::store(z_.data() + o, simd::select(movable, oz, simd::load(z_.data() + o)));
            continue;
        }
        alignas(64) float lx[W], ly[W], lz[W], lh[6][W];
        simd::store(lx, ox);
        simd::store(ly, oy);
        simd::store(lz, oz);
        for (std::size_t c = 0; c < 6; ++c) simd::store(lh[c], h[c]);
        for (std::size_t lane = 0; lane < W; ++lane) {
            if (inv_mass_[o + lane] == 0.0f) continue;
            float out[3] = {lx[lane], ly[lane], lz[lane]};
            const float hess[6] = {lh[0][lane], lh[1][lane], lh[2][lane], lh[3][lane], lh[4][lane], lh[5][lane]};
            keep_out(particle_[o + lane], o + lane, out, hess);
            x_[o + lane] = out[0];
            y_[o + lane] = out[1];
            z_[o + lane] = out[2];
        }
    }
    return r;
}

} // namespace drape::vbd
