// Worker threads that really run: a oneTBB task_arena of exactly the requested number of workers (also above the
// core count), with a global_control that lets TBB create that many. Everything parallel in drape runs inside
// Workers::run(); the number reported to users is workers(), the arena's concurrency, never the request alone.
#pragma once

#include <cstddef>
#include <memory>
#include <utility>

#include <tbb/global_control.h>
#include <tbb/task_arena.h>

namespace drape {

/// Allowed worker counts (flags, scene files, the viewer's Physics panel).
inline constexpr int min_workers = 1;
inline constexpr int max_workers = 256;

class Workers {
  public:
    /// count = 0: the hardware's default concurrency. Throws InvalidInput outside [1, 256].
    explicit Workers(int count = 0);
    /// Runs f inside the arena (blocking) and returns its result.
    template <class F> decltype(auto) run(F&& f) { return arena_->execute(std::forward<F>(f)); }
    /// Workers the arena runs (the calling thread included).
    int workers() const noexcept { return workers_; }
    /// Hardware threads of this machine (oneTBB's default concurrency).
    static int hardware() noexcept;

  private:
    int workers_ = 1;
    std::unique_ptr<tbb::global_control> control_;
    std::unique_ptr<tbb::task_arena> arena_;
};

} // namespace drape
