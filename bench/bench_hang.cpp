// Google Benchmark over BENCH.md's "hang" scene: N x threads for the full substep, plus one benchmark per pipeline
// stage. Counter `particle_substeps_per_second` is BENCH.md figure 1 (scene building excluded; the scene is cooked
// once per N and reused). Run bench/sweep.py for the CSV and plots in docs/.
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include <benchmark/benchmark.h>

#include "drape/scene_hang.hpp"
#include "drape/simulation.hpp"
#include "drape/stability.hpp"
#include "drape/workers.hpp"

namespace {

using namespace drape;

/// One simulation per (N, kernel, fused, model), cooked on first use and kept for the whole run.
Simulation& simulation(std::uint32_t n, KernelPath kernel, bool fused, MaterialModel model = MaterialModel::springs) {
    static std::map<std::tuple<std::uint32_t, KernelPath, bool, MaterialModel>, std::unique_ptr<Simulation>> cache;
    static std::mutex mutex;
    std::lock_guard lock(mutex);
    auto& slot = cache[{n, kernel, fused, model}];
    if (!slot) {
        HangParams hp;
        hp.n = n;
        // Fabric: the default Fabric with Rayleigh damping on (the kernel's cost does not depend on the figures).
        hp.model = model;
        hp.fabric.damping = 1e-4f;
        SceneBuild scene = build_hang_scene(hp);
        SimulationParams sp;
        sp.dt = static_cast<float>(default_dt(scene.cloth, sp.air_drag));
        sp.kernel = kernel;
        sp.fused = fused;
        slot = std::make_unique<Simulation>(std::move(scene.cloth), scene.initial, sp);
    }
    return *slot;
}

/// A task arena of exactly `threads` workers (also above the core count), one per count, kept for the whole
/// run.
Workers& workers(std::int64_t threads) {
    static std::map<std::int64_t, std::unique_ptr<Workers>> cache;
    static std::mutex mutex;
    std::lock_guard lock(mutex);
    auto& slot = cache[threads];
    if (!slot) slot = std::make_unique<Workers>(static_cast<int>(threads));
    return *slot;
}

/// Substeps per benchmark iteration: ~2e6 particle-substeps, so one iteration is a few milliseconds at any N.
std::size_t substeps_per_iteration(std::size_t particles) { return std::max<std::size_t>(1, 2'000'000 / particles); }

void set_labels(benchmark::State& state, const Simulation& sim, std::size_t substeps_per_iter) {
    const double ps = double(sim.cloth().particle_count) * double(substeps_per_iter);
    state.counters["particle_substeps_per_second"] =
        benchmark::Counter(ps * double(state.iterations()), benchmark::Counter::kIsRate);
    state.counters["particles"] = double(sim.cloth().particle_count);
    state.counters["springs"] = double(sim.cloth().spring_count());
    std::string stages;
    for (const std::string& s : sim.stage_names()) stages += (stages.empty() ? "" : "+") + s;
    state.SetLabel(std::string(kernel_path_name(sim.kernel())) + (sim.params().fused ? " fused " : " staged ") + stages);
}

/// Full substep (BENCH.md figure 1). Args: N, threads.
void run_substep(benchmark::State& state, KernelPath kernel, bool fused, MaterialModel model = MaterialModel::springs) {
    const auto n = static_cast<std::uint32_t>(state.range(0));
    Workers& w = workers(state.range(1));
    Simulation& sim = simulation(n, kernel, fused, model);
    const std::size_t k = substeps_per_iteration(sim.cloth().particle_count);
    w.run([&] {
        sim.step(k); // warm-up: caches, thread pool
        for (auto _ : state)
            sim.step(k);
    });
    set_labels(state, sim, k);
    state.counters["threads"] = double(w.workers());
    state.counters["bending_elements"] = double(sim.cloth().bending.elements.size());
}

void BM_Substep(benchmark::State& state) { run_substep(state, KernelPath::grid, true); }
void BM_SubstepCsr(benchmark::State& state) { run_substep(state, KernelPath::csr, true); }
void BM_SubstepStaged(benchmark::State& state) { run_substep(state, KernelPath::grid, false); }
/// The fabric model (membrane springs + bending stencil + Rayleigh damping) on the fused grid kernel: compare with
/// BM_Substep at the same N and threads (docs/performance.md, "Fabric model").
void BM_SubstepFabric(benchmark::State& state) {
    run_substep(state, KernelPath::grid, true, MaterialModel::fabric);
}
void BM_SubstepFabricCsr(benchmark::State& state) {
    run_substep(state, KernelPath::csr, true, MaterialModel::fabric);
}

/// One pipeline stage alone (staged form). Args: stage, N, threads.
void BM_Stage(benchmark::State& state) {
    const auto stage = static_cast<Stage>(state.range(0));
    const auto n = static_cast<std::uint32_t>(state.range(1));
    Workers& w = workers(state.range(2));
    Simulation& sim = simulation(n, KernelPath::grid, false);
    w.run([&] {
        sim.run_stage(stage);
        for (auto _ : state)
            sim.run_stage(stage);
    });
    state.counters["particle_substeps_per_second"] =
        benchmark::Counter(double(sim.cloth().particle_count) * double(state.iterations()), benchmark::Counter::kIsRate);
    state.counters["threads"] = double(w.workers());
    state.SetLabel(stage_name(stage));
}

/// One strain-limiting pass (levelled colour groups, 10 % limit) over a soft "hang" that has been stretched: the cost
/// per limited spring. Args: N, threads.
void BM_StrainLimit(benchmark::State& state) {
    const auto n = static_cast<std::uint32_t>(state.range(0));
    Workers& w = workers(state.range(1));
    static std::map<std::uint32_t, std::unique_ptr<Simulation>> cache;
    auto& slot = cache[n];
    if (!slot) {
        HangParams hp;
        hp.n = n;
        hp.stiffness = 100.0f;
        SceneBuild scene = build_hang_scene(hp);
        SimulationParams sp;
        sp.dt = static_cast<float>(default_dt(scene.cloth, sp.air_drag));
        sp.strain_limit = {0.1f, 1, 1};
        slot = std::make_unique<Simulation>(std::move(scene.cloth), scene.initial, sp);
        w.run([&] { slot->step(2000); }); // hanging and stretched
    }
    Simulation& sim = *slot;
    w.run([&] {
        for (auto _ : state)
            sim.run_stage(Stage::strain_limit);
    });
    const double springs = double(sim.strain_limit_groups().edge_index.size());
    state.counters["springs_per_second"] =
        benchmark::Counter(springs * double(state.iterations()), benchmark::Counter::kIsRate);
    state.counters["particle_substeps_per_second"] =
        benchmark::Counter(double(sim.cloth().particle_count) * double(state.iterations()), benchmark::Counter::kIsRate);
    state.counters["groups"] = double(sim.strain_limit_groups().group_count());
    state.counters["threads"] = double(w.workers());
    state.SetLabel("strain_limit pass");
}

void thread_args(benchmark::internal::Benchmark* b, std::initializer_list<std::int64_t> sizes) {
    const int hardware = Workers::hardware();
    for (std::int64_t n : sizes) {
        b->Args({n, 1});
        for (int t = 2; t <= hardware; ++t) b->Args({n, t});
    }
}

} // namespace

BENCHMARK(BM_Substep)
    ->ArgNames({"N", "threads"})
    ->Apply([](auto* b) { thread_args(b, {32, 100, 316, 1000}); })
    ->UseRealTime()
    ->MinTime(1.0)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SubstepCsr)
    ->ArgNames({"N", "threads"})
    ->Apply([](auto* b) { thread_args(b, {100, 316}); })
    ->UseRealTime()
    ->MinTime(1.0)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SubstepFabric)
    ->ArgNames({"N", "threads"})
    ->Apply([](auto* b) { thread_args(b, {100, 316, 1000}); })
    ->UseRealTime()
    ->MinTime(1.0)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SubstepFabricCsr)
    ->ArgNames({"N", "threads"})
    ->Apply([](auto* b) { thread_args(b, {316}); })
    ->UseRealTime()
    ->MinTime(1.0)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SubstepStaged)
    ->ArgNames({"N", "threads"})
    ->Apply([](auto* b) { thread_args(b, {316}); })
    ->UseRealTime()
    ->MinTime(1.0)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_StrainLimit)
    ->ArgNames({"N", "threads"})
    ->Apply([](auto* b) { thread_args(b, {100, 316}); })
    ->UseRealTime()
    ->MinTime(0.5)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Stage)
    ->ArgNames({"stage", "N", "threads"})
    ->Apply([](auto* b) {
        // The stages "hang" runs (the others are measured on scenes that use them: BM_StrainLimit, bench/garments.py).
        const int hardware = Workers::hardware();
        for (Stage s : {Stage::external_forces, Stage::spring_forces, Stage::integrate})
            for (std::int64_t n : {316, 1000})
                for (int t : {1, hardware}) b->Args({static_cast<int>(s), n, t});
    })
    ->UseRealTime()
    ->MinTime(0.5)
    ->Unit(benchmark::kMicrosecond);

BENCHMARK_MAIN();
