/* imm-monoslam — benchmark of the synthetic-sequence renderer (libs/sim): CSimulator::render of
 * ini/scenarios/handheld-moving.ini (textured room, moving boxes, sensor noise on) at 320x240 and
 * 640x480; time per rendered frame (the renderer's own threads). Formerly the ctest entry
 * SimSpeed.ReportFramesPerSecond, which printed and asserted nothing. */
#include "bench_common.h"

#include <immslam/sim/CSimulator.h>
#include <immslam/sim/TScenario.h>

#include <cstddef>
#include <string>

namespace
{
void BM_SimRender(benchmark::State& st)
{
  const std::string cam = st.range(0) == 320 ? "pinhole 320 240 240 240 159.5 119.5" : "pinhole 640 480 480 480 319.5 239.5";
  const immslam::sim::CSimulator sim(immslam::sim::TScenario::loadFile(
      immslam::bench::sourceDir() + "/ini/scenarios/handheld-moving.ini", {"scenario.camera=" + cam}));
  std::size_t k = 0;
  for (auto _ : st)
  {
    auto f = sim.render(k);
    benchmark::DoNotOptimize(f);
    k = (k + 1) % 30;
  }
  st.SetItemsProcessed(st.iterations());  // frames
}
BENCHMARK(BM_SimRender)->ArgName("width")->Arg(320)->Arg(640)->Unit(benchmark::kMillisecond)->UseRealTime();
}  // namespace

IMMSLAM_BENCHMARK_MAIN();
