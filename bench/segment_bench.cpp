// Segment-stage benchmark on the default-resolution phantom (0.7 mm, as the paper's CT):
// phantom generation, slice reading, segmentation and surface times, and peak memory.
#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "tactus/core/cli.hpp"
#include "tactus/data_samples/phantom.hpp"
#include "tactus/segment/run.hpp"

int main(int argc, char** argv) {
  using namespace tactus;
  CLI::App app{"tactus-bench-segment: segmentation and surface timings on the default phantom", "tactus-bench-segment"};
  cli::CommonOptions common;
  cli::add_common_options(app, common, "");
  std::string work = "out/bench/segment";
  samples::PhantomParams params;
  app.add_option("--work", work, "work folder")->capture_default_str();
  app.add_option("--voxel-mm", params.voxel_mm, "phantom voxel size")->capture_default_str();
  return cli::run(app, argc, argv, common, [&] {
    params.slice_mm = params.voxel_mm;
    const auto t0 = std::chrono::steady_clock::now();
    const auto ph = samples::make_hand_phantom(params);
    samples::write_slice_stack(ph.ct, std::filesystem::path(work) / "stack");
    const double t_phantom = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const auto report =
        segment::run_segment_stage(std::filesystem::path(work) / "stack", std::filesystem::path(work) / "out", segment::StageOptions{});
    rusage ru{};
    getrusage(RUSAGE_SELF, &ru);
    std::printf(
        "phantom %d x %d x %d voxels (%.1f M), %.2f mm: phantom+stack %.2f s, read %.2f s, segment %.2f s, surfaces %.2f s, "
        "peak memory %.0f MB\n",
        ph.ct.dims[0], ph.ct.dims[1], ph.ct.dims[2], static_cast<double>(ph.ct.size()) / 1e6, params.voxel_mm, t_phantom,
        report["time_s"]["read"].get<double>(), report["time_s"]["segment"].get<double>(), report["time_s"]["surfaces"].get<double>(),
        static_cast<double>(ru.ru_maxrss) / 1024.0);
  });
}
