// One loop over fixed work units (particle blocks, spring chunks): in parallel with oneTBB, or on the calling thread
// in index order (the serial twin). Each unit writes only its own outputs, so both give the same bits.
#pragma once

#include <cstddef>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace drape {

template <bool Parallel, class F> void for_each_index(std::size_t count, F&& f) {
    if constexpr (Parallel) {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 1), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t k = r.begin(); k != r.end(); ++k) f(k);
        });
    } else {
        for (std::size_t k = 0; k < count; ++k) f(k);
    }
}

} // namespace drape
