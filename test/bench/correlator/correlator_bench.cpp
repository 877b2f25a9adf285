// bench-correlator: messages per second through modes original and pose-corrected on a generated 5-UGV mission with
// heading biases and offsets (the target: at least 100,000 observations per second on one core), and the
// stored observation points after it (bounded). state.range(0): mission length [s]. Snapshots (1 per second) are
// excluded from the timing: they are output, timed by `ugvsense correlate`.
#include <benchmark/benchmark.h>

#include "ugv/correlator/original_correlator.hpp"
#include "ugv/correlator/pose_corrected_correlator.hpp"
#include "ugv/correlator/scenario.hpp"

namespace {

using namespace ugv::correlator;

const Scenario& mission(double durationS)
{
    static double cachedFor = -1.0;
    static Scenario cached;
    if (cachedFor != durationS) {
        ScenarioConfig config = scenarioPreset(ScenarioSetting::Bias);
        config.durationS = durationS;
        cached = generateScenario(config).value();
        cachedFor = durationS;
    }
    return cached;
}

template <class Correlator>
void BM_Correlator(benchmark::State& state)
{
    const Scenario& s = mission(static_cast<double>(state.range(0)));
    std::size_t stored = 0;
    for (auto _ : state) {
        Correlator sut;
        double next = 1.0;
        for (const Message& m : s.messages) {
            const double t = std::visit([](const auto& v) { return v.t; }, m);
            while (t >= next) {
                state.PauseTiming(); // the throughput of add(); snapshots are output, timed by `correlate`
                sut.advance(next);
                benchmark::DoNotOptimize(sut.snapshot(next));
                state.ResumeTiming();
                next += 1.0;
            }
            benchmark::DoNotOptimize(sut.add(m));
        }
        stored = sut.storedPoints();
    }
    state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(s.messages.size()));
    state.counters["messages"] = static_cast<double>(s.messages.size());
    state.counters["stored_points"] = static_cast<double>(stored);
}

BENCHMARK(BM_Correlator<OriginalCorrelator>)
    ->Name("BM_OriginalCorrelator")
    ->Arg(600)
    ->Arg(12600)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);
BENCHMARK(BM_Correlator<PoseCorrectedCorrelator>)
    ->Name("BM_PoseCorrectedCorrelator")
    ->Arg(600)
    ->Arg(12600)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);

} // namespace

BENCHMARK_MAIN();
