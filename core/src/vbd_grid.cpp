// Cooking and packing of the grid layout of vertex block descent (vbd_grid.hpp).
#include "vbd_grid.hpp"

#include <algorithm>

#include "drape/cloth.hpp"
#include "for_each_index.hpp"

namespace drape::vbd {

namespace {

std::int32_t floor_div(std::int32_t a, std::int32_t p) noexcept { return a >= 0 ? a / p : -((-a + p - 1) / p); }

/// The slot list of one kind of row (springs or bending): every (dr, dc) that occurs, ascending; per entry its slot.
/// False when an entry reaches further than two rows or columns or a row is not in ascending slot order.
bool directions(const std::vector<std::uint32_t>& offsets, const std::vector<std::uint32_t>& neighbour,
                std::uint32_t columns, std::vector<std::array<std::int32_t, 2>>& dirs,
                std::vector<std::uint8_t>& slot) {
    const std::size_t n = offsets.size() - 1;
    auto dir_of = [&](std::size_t i, std::uint32_t j) {
        const std::int32_t dr = std::int32_t(j / columns) - std::int32_t(i / columns);
        const std::int32_t dc = std::int32_t(j % columns) - std::int32_t(i % columns);
        return std::array<std::int32_t, 2>{dr, dc};
    };
    // (dr, dc) in [-2, 2]^2 -> its slot, through a 5 x 5 table (a search of dirs per entry was 1.4 s of the 5 s
    // cook of a million-particle cloth).
    std::array<int, 25> slot_of{};
    slot_of.fill(-1);
    auto cell_of = [](const std::array<std::int32_t, 2>& d) { return std::size_t((d[0] + 2) * 5 + (d[1] + 2)); };
    for (std::size_t i = 0; i < n; ++i)
        for (std::uint32_t e = offsets[i]; e < offsets[i + 1]; ++e) {
            const auto d = dir_of(i, neighbour[e]);
            if (d[0] < -2 || d[0] > 2 || d[1] < -2 || d[1] > 2) return false;
            slot_of[cell_of(d)] = 0;
        }
    dirs.clear();
    for (std::int32_t dr = -2; dr <= 2; ++dr) // ascending (dr, dc): the sorted order
        for (std::int32_t dc = -2; dc <= 2; ++dc) {
            const std::array<std::int32_t, 2> d{dr, dc};
            if (slot_of[cell_of(d)] < 0) continue;
            slot_of[cell_of(d)] = int(dirs.size());
            dirs.push_back(d);
        }
    slot.assign(neighbour.size(), 0);
    for (std::size_t i = 0; i < n; ++i) {
        int last = -1;
        for (std::uint32_t e = offsets[i]; e < offsets[i + 1]; ++e) {
            const int s = slot_of[cell_of(dir_of(i, neighbour[e]))];
            if (s <= last) return false; // the scalar reference's order differs from the slots' (or a duplicate)
            slot[e] = std::uint8_t(s);
            last = s;
        }
    }
    return true;
}

} // namespace

std::unique_ptr<GridLayout> GridLayout::cook(const VbdGraph& g, std::uint32_t rows, std::uint32_t columns) {
    const std::size_t n = g.particle_count;
    if (rows == 0 || columns == 0 || std::size_t(rows) * columns != n || g.colour_count() == 0) return nullptr;
    auto L = std::make_unique<GridLayout>();
    std::vector<std::uint8_t> spring_slot, bend_slot;
    if (!directions(g.spring_offsets, g.spring_neighbour, columns, L->spring_dir_, spring_slot)) return nullptr;
    const bool bending = !g.bend_diag.empty();
    if (bending && !directions(g.bend_offsets, g.bend_neighbour, columns, L->bend_dir_, bend_slot)) return nullptr;

    // The colouring must be the pattern (row mod P, column mod P): one class per colour and one colour per class.
    std::vector<std::uint32_t> colour(n);
    for (std::size_t c = 0; c < g.colour_count(); ++c)
        for (std::uint32_t k = g.colour_offsets[c]; k < g.colour_offsets[c + 1]; ++k) colour[g.colour_vertex[k]] = c;
    std::uint32_t period = 0;
    for (std::uint32_t P : {2u, 3u}) {
        std::vector<std::uint32_t> class_colour(P * P, UINT32_MAX), colour_class(g.colour_count(), UINT32_MAX);
        bool fits = true;
        for (std::size_t i = 0; i < n && fits; ++i) {
            const std::uint32_t cls = (std::uint32_t(i / columns) % P) * P + std::uint32_t(i % columns) % P;
            const std::uint32_t c = colour[i];
            if (class_colour[cls] == UINT32_MAX) class_colour[cls] = c;
            if (colour_class[c] == UINT32_MAX) colour_class[c] = cls;
            fits = class_colour[cls] == c && colour_class[c] == cls;
        }
        if (fits) {
            period = P;
            L->colour_class_ = colour_class;
            break;
        }
    }
    if (period == 0) return nullptr;
    L->period_ = period;
    L->columns_ = columns;
    L->particles_ = n;
    const std::size_t sub_rows = (rows + period - 1) / period, sub_columns = (columns + period - 1) / period;
    constexpr std::size_t W = simd::width;
    auto round_up = [](std::size_t v) { return (v + W - 1) / W * W; };
    L->stride_ = std::uint32_t(sub_columns + 1);
    const std::size_t stride = L->stride_, span = sub_rows * stride - 1; // first to last cell
    L->batches_ = (span + W - 1) / W;
    // Halo lanes load neighbours up to stride + 1 cells before the first cell and after the last batch; a class's
    // halo (row -1 ... row sub_rows) and its batches stay clear of the next class's.
    L->front_ = round_up(stride + 1);
    L->region_ = round_up((sub_rows + 2) * stride + W);
    L->cells_ = L->front_ + std::size_t(period) * period * L->region_;
    // Chunks of about 64 cells: a coarse level's colour then still splits into several chunks. Against 256
    // (2-core AVX2 machine, drape_implicit throughput, 2 threads, alternating builds): N = 316 per iteration
    // 6.50 / 6.57 -> 6.06 / 6.02 ms, N = 100 1.08 / 1.09 -> 1.05 / 1.06 ms; 16 cells: no better than 64.
    L->batches_per_chunk_ = std::max<std::size_t>(1, 64 / W);
    L->chunks_ = (L->batches_ + L->batches_per_chunk_ - 1) / L->batches_per_chunk_;

    L->cell_of_.resize(n);
    L->particle_.reset(L->cells_);
    std::fill_n(L->particle_.data(), L->cells_, UINT32_MAX);
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint32_t r = std::uint32_t(i / columns), c = std::uint32_t(i % columns);
        const std::size_t cell =
            L->cell((r % period) * period + c % period, std::int32_t(r / period), std::int32_t(c / period));
        L->cell_of_[i] = std::uint32_t(cell);
        L->particle_[cell] = std::uint32_t(i);
    }
    auto deltas = [&](const std::vector<std::array<std::int32_t, 2>>& dirs, std::vector<std::int32_t>& out) {
        out.assign(std::size_t(period) * period * dirs.size(), 0);
        const std::int32_t P = std::int32_t(period);
        for (std::int32_t a = 0; a < P; ++a)
            for (std::int32_t b = 0; b < P; ++b)
                for (std::size_t s = 0; s < dirs.size(); ++s) {
                    const std::int32_t ar = a + dirs[s][0], bc = b + dirs[s][1];
                    const std::int32_t fa = floor_div(ar, P), fb = floor_div(bc, P);
                    const std::uint32_t to = std::uint32_t((ar - fa * P) * P + (bc - fb * P));
                    // Cell of (p, q) in class (a, b) and of (p + fa, q + fb) in class `to`, both at p = q = 1.
                    const std::int64_t own = std::int64_t(L->cell(std::uint32_t(a * P + b), 1, 1));
                    const std::int64_t other = std::int64_t(L->cell(to, 1 + fa, 1 + fb));
                    out[std::size_t(a * P + b) * dirs.size() + s] = std::int32_t(other - own);
                }
    };
    deltas(L->spring_dir_, L->spring_delta_);
    deltas(L->bend_dir_, L->bend_delta_);

    for (AlignedArray<float>* f : {&L->x_, &L->y_, &L->z_, &L->x0_, &L->y0_, &L->z0_, &L->px_, &L->py_, &L->pz_,
                                   &L->inv_mass_, &L->diag_, &L->dh_[0], &L->dh_[1], &L->dh_[2], &L->dh_[3],
                                   &L->dh_[4], &L->dh_[5]}) {
        f->reset(L->cells_);
        std::fill_n(f->data(), L->cells_, 0.0f);
    }
    for (AlignedArray<float>* f : {&L->k_, &L->kd_, &L->rest_, &L->dq_}) {
        f->reset(L->spring_dir_.size() * L->cells_);
        std::fill_n(f->data(), f->size(), 0.0f);
    }
    L->q_.reset(std::max<std::size_t>(1, L->bend_dir_.size()) * L->cells_);
    L->refresh(g);
    return L;
}

void GridLayout::refresh(const VbdGraph& g) {
    const std::size_t n = particles_;
    for (AlignedArray<float>* f : {&k_, &kd_, &rest_, &q_}) std::fill_n(f->data(), f->size(), 0.0f);
    std::fill_n(diag_.data(), cells_, 0.0f);
    for (std::size_t i = 0; i < n; ++i) {
        const std::size_t c = cell_of_[i];
        const std::size_t cls = class_of(i);
        for (std::uint32_t e = g.spring_offsets[i], s = 0; e < g.spring_offsets[i + 1]; ++e) {
            // The entry's slot: the one whose delta reaches its neighbour's cell (distinct neighbours, distinct
            // cells; cook checked that rows run in ascending slot order).
            const std::int64_t d = std::int64_t(cell_of_[g.spring_neighbour[e]]) - std::int64_t(c);
            while (spring_delta_[cls * spring_dir_.size() + s] != d) ++s;
            k_[spring_at(c, s)] = g.spring_k[e];
            kd_[spring_at(c, s)] = g.spring_kd[e];
            rest_[spring_at(c, s)] = g.spring_rest[e];
        }
        if (g.bend_diag.empty()) continue;
        diag_[c] = g.bend_diag[i];
        for (std::uint32_t e = g.bend_offsets[i], s = 0; e < g.bend_offsets[i + 1]; ++e) {
            const std::int64_t d = std::int64_t(cell_of_[g.bend_neighbour[e]]) - std::int64_t(c);
            while (bend_delta_[cls * bend_dir_.size() + s] != d) ++s;
            q_[bend_at(c, s)] = g.bend_q[e];
        }
    }
}

void GridLayout::refresh_rest(const VbdGraph& g) {
    for (std::size_t i = 0; i < particles_; ++i) {
        const std::size_t c = cell_of_[i];
        const std::size_t cls = class_of(i);
        for (std::uint32_t e = g.spring_offsets[i], s = 0; e < g.spring_offsets[i + 1]; ++e) {
            const std::int64_t d = std::int64_t(cell_of_[g.spring_neighbour[e]]) - std::int64_t(c);
            while (spring_delta_[cls * spring_dir_.size() + s] != d) ++s; // the entry's slot, as in refresh
            rest_[spring_at(c, s)] = g.spring_rest[e];
        }
    }
}

template <bool Parallel>
void GridLayout::pack(const LevelState& s, const float* px, const float* py, const float* pz) {
    const std::size_t n = particles_;
    for_each_index<Parallel>((n + block_particles - 1) / block_particles, [&](std::size_t blk) {
        for (std::size_t i = blk * block_particles, end = std::min(n, (blk + 1) * block_particles); i < end; ++i) {
            const std::size_t c = cell_of_[i];
            x_[c] = s.x[i];
            y_[c] = s.y[i];
            z_[c] = s.z[i];
            x0_[c] = s.x0[i];
            y0_[c] = s.y0[i];
            z0_[c] = s.z0[i];
            px_[c] = px[i];
            py_[c] = py[i];
            pz_[c] = pz[i];
            inv_mass_[c] = s.inv_mass[i];
        }
    });
}

template <bool Parallel> void GridLayout::unpack(const LevelState& s) const {
    const std::size_t n = particles_;
    for_each_index<Parallel>((n + block_particles - 1) / block_particles, [&](std::size_t blk) {
        for (std::size_t i = blk * block_particles, end = std::min(n, (blk + 1) * block_particles); i < end; ++i) {
            const std::size_t c = cell_of_[i];
            s.x[i] = x_[c];
            s.y[i] = y_[c];
            s.z[i] = z_[c];
        }
    });
}

template <bool Parallel> void GridLayout::cook_damping(const SweepArgs& a) {
    constexpr std::size_t W = simd::width;
    const simd::fbatch inv_h(a.inv_h);
    const std::size_t slots = spring_dir_.size();
    for_each_index<Parallel>(colour_count() * chunks_, [&](std::size_t job) {
        const std::uint32_t cls = colour_class_[job / chunks_];
        const std::size_t chunk = job % chunks_;
        const std::int32_t* sd = spring_delta_.data() + std::size_t(cls) * slots;
        const std::int32_t* bd = bend_delta_.data() + std::size_t(cls) * bend_dir_.size();
        for (std::size_t b = chunk * batches_per_chunk_, b1 = std::min(batches_, b + batches_per_chunk_); b < b1; ++b) {
            const std::size_t o = class_base(cls) + b * W;
            const GridSource src{*this, o, sd, bd};
            const simd::fbatch x0i = src.own(a.x0), y0i = src.own(a.y0), z0i = src.own(a.z0);
            DampingHessian<simd::fbatch> h;
            for (std::size_t s = 0; s < slots; ++s) {
                simd::fbatch x0j, y0j, z0j;
                src.spring_pos(s, a.x0, a.y0, a.z0, x0j, y0j, z0j);
                const simd::fbatch nx = x0j - x0i, ny = y0j - y0i, nz = z0j - z0i;
                const simd::fbatch q = damping_q(src.spring_kd(s), inv_h, nx, ny, nz);
                h.add(q, nx, ny, nz);
                simd::store(dq_.data() + spring_at(o, s), q);
            }
            simd::store(dh_[0].data() + o, h.xx);
            simd::store(dh_[1].data() + o, h.yy);
            simd::store(dh_[2].data() + o, h.zz);
            simd::store(dh_[3].data() + o, h.xy);
            simd::store(dh_[4].data() + o, h.xz);
            simd::store(dh_[5].data() + o, h.yz);
        }
    });
}

SweepArgs GridLayout::packed_args(SweepArgs a) noexcept {
    a.x0 = x0_.data();
    a.y0 = y0_.data();
    a.z0 = z0_.data();
    a.px = px_.data();
    a.py = py_.data();
    a.pz = pz_.data();
    a.x = x_.data();
    a.y = y_.data();
    a.z = z_.data();
    a.inv_mass = inv_mass_.data();
    return a;
}

template void GridLayout::pack<true>(const LevelState&, const float*, const float*, const float*);
template void GridLayout::pack<false>(const LevelState&, const float*, const float*, const float*);
template void GridLayout::cook_damping<true>(const SweepArgs&);
template void GridLayout::cook_damping<false>(const SweepArgs&);
template void GridLayout::unpack<true>(const LevelState&) const;
template void GridLayout::unpack<false>(const LevelState&) const;

} // namespace drape::vbd
