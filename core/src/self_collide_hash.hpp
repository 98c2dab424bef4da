// Self-collision's spatial hash of patch boxes (self_collide.cpp): which patches' boxes overlap. Used for the boxes of
// a round (where the patches are now, grown by the thickness) and for the swept boxes of a run (the whole motion the
// run covers), which bound the relative motion that sets the run's parts.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace drape {

/// Two boxes (6 floats each: lo x y z, hi x y z) meet (touching counts).
inline bool boxes_meet(const float* a, const float* b) noexcept {
    return a[3] >= b[0] && b[3] >= a[0] && a[4] >= b[1] && b[4] >= a[1] && a[5] >= b[2] && b[5] >= a[2];
}

/// Cubic cells as wide as the widest box, so that a box spans at most 2 cells an axis (8 buckets); each pair of
/// overlapping boxes is reported once, in the bucket of the cell holding the low corner of their intersection.
/// Filled by counting sort, serially (there are about 30 times fewer patches than particles); the bucket arrays are the
/// caller's (sized when the patches are cooked: a power of two >= 2 per patch, 8 items per patch), so no allocation.
class PatchHash {
  public:
    /// `box`: 6 floats per patch (lo x y z, hi x y z).
    PatchHash(const float* box, std::size_t patches, std::vector<std::uint32_t>& count,
              std::vector<std::uint32_t>& start, std::vector<std::uint32_t>& items)
        : box_(box), start_(start.data()), items_(items.data()), mask_(std::uint32_t(count.size() - 1)) {
        float widest = 0.0f;
        for (std::size_t p = 0; p < patches; ++p)
            for (int c = 0; c < 3; ++c) widest = std::max(widest, box[6 * p + 3 + c] - box[6 * p + c]);
        inv_cell_ = widest > 0.0f ? 1.0f / (1.01f * widest) : 1.0f;
        std::fill(count.begin(), count.end(), 0u);
        for (std::size_t p = 0; p < patches; ++p)
            each_bucket(p, [&](std::uint32_t bk, bool again) { count[bk] += again ? 0 : 1; });
        start[0] = 0;
        for (std::size_t k = 0; k < count.size(); ++k) {
            start[k + 1] = start[k] + count[k];
            count[k] = start[k]; // now the bucket's fill cursor
        }
        for (std::size_t p = 0; p < patches; ++p)
            each_bucket(p, [&](std::uint32_t bk, bool again) {
                if (!again) items[count[bk]++] = std::uint32_t(p);
            });
    }

    /// Calls f(q) for every patch q > p whose box overlaps p's; over all p, each such pair once.
    template <class F> void overlapping(std::uint32_t p, F&& f) const {
        const float* bp = box_ + 6 * std::size_t(p);
        each_bucket(p, [&](std::uint32_t bk, bool again) {
            if (again) return; // this bucket was searched for another of p's cells
            for (std::uint32_t k = start_[bk]; k < start_[bk + 1]; ++k) {
                const std::uint32_t q = items_[k];
                if (q <= p) continue;
                const float* bq = box_ + 6 * std::size_t(q);
                if (!boxes_meet(bp, bq)) continue;
                // The pair once: where the low corner of the two boxes' intersection lies (in p's cells and in q's,
                // so q is in that cell's bucket).
                if (bucket_of(cell_of(std::max(bp[0], bq[0])), cell_of(std::max(bp[1], bq[1])),
                              cell_of(std::max(bp[2], bq[2]))) != bk)
                    continue;
                f(q);
            }
        });
    }

  private:
    std::int64_t cell_of(float v) const noexcept { return std::int64_t(std::floor(v * inv_cell_)); }
    std::uint32_t bucket_of(std::int64_t i, std::int64_t j, std::int64_t k) const noexcept {
        std::uint64_t h = std::uint64_t(i) * 0x9E3779B185EBCA87ull ^ std::uint64_t(j) * 0xC2B2AE3D27D4EB4Full ^
                          std::uint64_t(k) * 0x165667B19E3779F9ull;
        h ^= h >> 29;
        h *= 0xBF58476D1CE4E5B9ull;
        h ^= h >> 32;
        return std::uint32_t(h) & mask_;
    }
    /// f(bucket, again) for each cell p's box spans; again: the bucket was already given for another of its cells.
    template <class F> void each_bucket(std::size_t p, F&& f) const {
        const float* b = box_ + 6 * p;
        std::int64_t lo[3];
        int cnt[3];
        for (int c = 0; c < 3; ++c) lo[c] = cell_of(b[c]), cnt[c] = cell_of(b[3 + c]) > lo[c] ? 2 : 1;
        std::uint32_t seen[8];
        int nseen = 0;
        for (int i = 0; i < cnt[0]; ++i)
            for (int j = 0; j < cnt[1]; ++j)
                for (int k = 0; k < cnt[2]; ++k) {
                    const std::uint32_t bk = bucket_of(lo[0] + i, lo[1] + j, lo[2] + k);
                    f(bk, std::find(seen, seen + nseen, bk) != seen + nseen);
                    seen[nseen++] = bk;
                }
    }

    const float* box_;
    const std::uint32_t* start_;
    const std::uint32_t* items_;
    std::uint32_t mask_;
    float inv_cell_ = 1.0f;
};

} // namespace drape
