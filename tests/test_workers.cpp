// drape::Workers runs exactly the requested number of worker threads, also above the machine's core count:
// inside a Workers(N) arena, N tasks that each wait (up to 5 s) for N distinct threads to arrive all see N
// distinct threads. A task that blocks keeps its thread, so the N tasks can only all arrive on N different
// threads.
#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <set>
#include <thread>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>

#include "drape/errors.hpp"
#include "drape/workers.hpp"

using namespace drape;

namespace {

/// Distinct threads that ran one of `count` tasks inside `workers`, each task waiting until `count` distinct
/// threads have arrived or `wait` has passed.
std::size_t threads_seen(Workers& workers, int count,
                         std::chrono::milliseconds wait = std::chrono::seconds(5)) {
    std::mutex m;
    std::condition_variable cv;
    std::set<std::thread::id> ids;
    const auto deadline = std::chrono::steady_clock::now() + wait;
    workers.run([&] {
        tbb::parallel_for(
            tbb::blocked_range<int>(0, count, 1),
            [&](const tbb::blocked_range<int>&) {
                std::unique_lock lock(m);
                ids.insert(std::this_thread::get_id());
                cv.notify_all();
                cv.wait_until(lock, deadline, [&] { return ids.size() >= std::size_t(count); });
            },
            tbb::simple_partitioner());
    });
    return ids.size();
}

TEST(Workers, RunsExactlyTheRequestedThreadsAboveTheCoreCount) {
    // 5 and 8 exceed the 2 cores of the development machine; every count really runs that many threads.
    for (int n : {1, 2, 3, 5, 8}) {
        Workers w(n);
        EXPECT_EQ(w.workers(), n);
        EXPECT_EQ(threads_seen(w, n), std::size_t(n)) << n << " workers requested";
    }
}

TEST(Workers, NeverRunsMoreThanRequested) {
    // 3 workers, 6 blocking tasks: only 3 threads can ever be inside (every task waits the full second for a
    // 6th).
    Workers w(3);
    EXPECT_EQ(threads_seen(w, 6, std::chrono::seconds(1)), 3u);
}

TEST(Workers, DefaultIsTheHardwareAndRangeIsChecked) {
    EXPECT_EQ(Workers().workers(), Workers::hardware());
    EXPECT_GE(Workers::hardware(), 1);
    EXPECT_THROW(Workers(-1), InvalidInput);
    EXPECT_THROW(Workers(max_workers + 1), InvalidInput);
    try {
        Workers w(257);
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("[1, 256]"), std::string::npos) << e.what();
    }
}

} // namespace
