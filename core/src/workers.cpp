#include "drape/workers.hpp"

#include <string>

#include <tbb/info.h>

#include "drape/errors.hpp"

namespace drape {

int Workers::hardware() noexcept { return tbb::info::default_concurrency(); }

Workers::Workers(int count) {
    if (count == 0) count = hardware();
    if (count < min_workers || count > max_workers)
        throw InvalidInput("threads = " + std::to_string(count) + " is outside the allowed range [" +
                           std::to_string(min_workers) + ", " + std::to_string(max_workers) + "]");
    workers_ = count;
    // The global limit must admit `count` threads or the arena would get fewer workers than it asks for; it is
    // never lowered below the hardware's (other arenas in the process keep theirs).
    const std::size_t limit = static_cast<std::size_t>(count > hardware() ? count : hardware());
    control_ = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, limit);
    arena_ = std::make_unique<tbb::task_arena>(count);
    arena_->initialize();
}

} // namespace drape
