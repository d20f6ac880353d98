// tactus-post: results folder -> report folder (summary.json, summary.md, PNG pictures and plots).
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <vector>

#include "tactus/core/cli.hpp"
#include "tactus/core/error.hpp"
#include "tactus/core/log.hpp"
#include "tactus/core/staged_output.hpp"
#include "tactus/postproc/render.hpp"
#include "tactus/postproc/results.hpp"
#include "tactus/postproc/summary.hpp"

namespace {
// VTK renders through X: without a display, run this same command under xvfb-run once.
void ensure_display(int argc, char** argv, bool pictures) {
  if (!pictures || std::getenv("DISPLAY") || std::getenv("TACTUS_POST_UNDER_XVFB")) return;
  if (std::system("command -v xvfb-run > /dev/null 2>&1") != 0) return;  // reported when rendering fails
  setenv("TACTUS_POST_UNDER_XVFB", "1", 1);
  std::vector<char*> args{const_cast<char*>("xvfb-run"), const_cast<char*>("-a"), const_cast<char*>("-s"),
                          const_cast<char*>("-screen 0 1600x1200x24")};
  for (int i = 0; i < argc; ++i) args.push_back(argv[i]);
  args.push_back(nullptr);
  execvp("xvfb-run", args.data());
}
}  // namespace

int main(int argc, char** argv) {
  using namespace tactus;
  CLI::App app{"tactus-post: a results folder of tactus-solve -> report with the stress and contact-pressure pictures, "
               "time plots, summary.json and summary.md",
               "tactus-post"};
  cli::CommonOptions common;
  cli::add_common_options(app, common, "report folder (default: report next to the results folder)");
  std::string results_dir;
  std::vector<double> times;
  bool no_pictures = false;
  app.add_option("results", results_dir, "results folder (results.pvd, history.csv, run.json)")->required();
  app.add_option("--times", times, "times (s) of the von Mises pictures, nearest output state (default: all)");
  app.add_flag("--no-pictures", no_pictures, "numbers only (no rendering, no display needed)");
  bool wants_pictures = true;
  for (int i = 1; i < argc; ++i) wants_pictures = wants_pictures && std::string(argv[i]) != "--no-pictures";
  ensure_display(argc, argv, wants_pictures);
  return cli::run(app, argc, argv, common, [&] {
    const postproc::Results results = postproc::read_results(results_dir);
    postproc::Summary summary = postproc::summarize(results);
    const std::filesystem::path out = common.output.empty()
                                          ? std::filesystem::path(results_dir).parent_path() / "report"
                                          : std::filesystem::path(common.output);
    StagedOutput staged(out);
    std::filesystem::create_directories(staged.path());
    if (!no_pictures) {
      if (!std::getenv("DISPLAY"))
        throw InputError("display", "DISPLAY", "an X display for VTK's off-screen rendering (install xvfb: apt-get install xvfb)",
                         "none; use --no-pictures for the numbers only");
      postproc::RenderOptions ro;
      ro.times = times;
      summary.pictures = postproc::render_report(results, summary, staged.path(), ro);
    }
    std::ofstream(staged.path() / "summary.json") << postproc::summary_json(summary);
    std::ofstream(staged.path() / "summary.md") << postproc::summary_markdown(summary);
    staged.commit();
    log::info() << "report: " << (out / "summary.md").string() << " (" << summary.pictures.size() << " pictures)";
  });
}
