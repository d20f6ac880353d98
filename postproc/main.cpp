// tactus-post: results folder -> report folder (summary.json, summary.md, PNG pictures and plots).
#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <memory>
#include <string>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <vector>

#include "tactus/core/cli.hpp"
#include "tactus/core/error.hpp"
#include "tactus/core/file_io.hpp"
#include "tactus/core/interrupt.hpp"
#include "tactus/core/log.hpp"
#include "tactus/core/output.hpp"
#include "tactus/postproc/render.hpp"
#include "tactus/postproc/results.hpp"
#include "tactus/postproc/summary.hpp"
#include "tactus/postproc/web_report.hpp"

namespace {
// VTK renders through X. Without a display, start a private Xvfb for the rendering, on a display
// number derived from our pid and retried on another if taken (concurrent runs each get their own
// server); -displayfd tells when it accepts connections. Measured: 8 concurrent runs under
// `xvfb-run -a` crashed 2-6 times, with private -noreset servers none did.
class VirtualDisplay {
 public:
  VirtualDisplay() {
    for (int attempt = 0; attempt < 8; ++attempt) {
      const int number = 100 + static_cast<int>((static_cast<unsigned>(getpid()) * 7919u + 104729u * static_cast<unsigned>(attempt)) % 30000u);
      if (start(number)) {
        setenv("DISPLAY", (":" + std::to_string(number)).c_str(), 1);
        return;
      }
    }
    throw tactus::InputError("display", "DISPLAY", "an X display, or Xvfb to start one (apt-get install xvfb)",
                             "none; use --no-pictures for the numbers only");
  }
  ~VirtualDisplay() { stop(); }
  VirtualDisplay(const VirtualDisplay&) = delete;
  VirtualDisplay& operator=(const VirtualDisplay&) = delete;

 private:
  bool start(int number) {
    int fds[2];
    if (pipe(fds) != 0) return false;
    pid_ = fork();
    if (pid_ == 0) {
      prctl(PR_SET_PDEATHSIG, SIGTERM);  // no server left behind if tactus-post dies
      tactus::unblock_stop_signals();    // (tactus-post blocks them for its interrupt watcher)
      close(fds[0]);
      const std::string fd = std::to_string(fds[1]), display = ":" + std::to_string(number);
      const int null = open("/dev/null", O_WRONLY);
      if (null >= 0) dup2(null, STDERR_FILENO), dup2(null, STDOUT_FILENO);
      // -noreset: VTK opens and closes a connection per window; a server resetting after the last
      // client left refuses the next one for a moment ("bad X server connection" under load).
      execlp("Xvfb", "Xvfb", display.c_str(), "-displayfd", fd.c_str(), "-screen", "0", "2400x1200x24", "-nolisten", "tcp", "-noreset",
             static_cast<char*>(nullptr));
      _exit(127);
    }
    close(fds[1]);
    std::string reported;
    char c;
    while (pid_ > 0 && read(fds[0], &c, 1) == 1 && c != '\n') reported += c;
    close(fds[0]);
    if (pid_ > 0 && reported == std::to_string(number)) return true;
    stop();
    return false;
  }
  void stop() {
    if (pid_ > 0) {
      kill(pid_, SIGTERM);
      waitpid(pid_, nullptr, 0);
      pid_ = -1;
    }
  }
  pid_t pid_ = -1;
};
// --probe x,y,z (metres), each.
std::vector<tactus::Vec3> probe_points(const std::vector<std::string>& probes) {
  std::vector<tactus::Vec3> points;
  for (const std::string& p : probes) {
    tactus::Vec3 x{};
    char comma1 = 0, comma2 = 0, rest = 0;
    if (std::sscanf(p.c_str(), "%lf %c %lf %c %lf %c", &x[0], &comma1, &x[1], &comma2, &x[2], &rest) != 5 || comma1 != ',' || comma2 != ',' ||
        !std::isfinite(x[0]) || !std::isfinite(x[1]) || !std::isfinite(x[2]))
      throw tactus::InputError("command line", "--probe", "a point x,y,z in metres, e.g. --probe 0.01,0.02,0.005", "\"" + p + "\"");
    points.push_back(x);
  }
  return points;
}
}  // namespace

int main(int argc, char** argv) {
  using namespace tactus;
  CLI::App app{
      "tactus-post: a results folder of tactus-solve -> report with the stress and contact-pressure pictures, "
      "time plots, summary.json and summary.md",
      "tactus-post"};
  cli::CommonOptions common;
  cli::add_common_options(app, common, "report folder (default: report next to the results folder)");
  std::string results_dir;
  std::vector<double> times;
  bool no_pictures = false, no_html = false;
  app.add_option("results", results_dir, "results folder (results.pvd, history.csv, run.json)")->required();
  app.add_option("--times", times, "times (s) of the von Mises pictures, nearest output state (default: all)");
  app.add_flag("--no-pictures", no_pictures, "no PNG pictures or plots (no rendering, no display needed)");
  app.add_flag("--no-html", no_html, "no interactive report (index.html and data/)");
  std::vector<std::string> probes;
  app.add_option("--probe", probes,
                 "x,y,z in m (reference configuration): the contact pressure against time at the surface node nearest it, "
                 "in probes.csv (repeat for more points)");
  postproc::RenderOptions ro;
  std::vector<double> view, section_normal;
  app.add_option("--pressure-body", ro.pressure_body, "body the pressure map shows (default: the one carrying the highest pressure)");
  app.add_option("--view", view,
                 "direction from the model to the camera of the stress pictures, x y z "
                 "(default: along the model's axis of least extent)")
      ->expected(3);
  app.add_option("--section-normal", section_normal,
                 "normal of the section plane, x y z (default: the longest axis of the "
                 "body carrying the pressure)")
      ->expected(3);
  return cli::run(app, argc, argv, common, [&] {
    postproc::WebReportOptions wo;
    wo.page = !no_html;
    wo.probes = probe_points(probes);
    const std::filesystem::path out =
        common.output.empty() ? std::filesystem::path(results_dir).parent_path() / "report" : std::filesystem::path(common.output);
    OutputFolder staged(out, common.output_rules({results_dir}));
    const postproc::Results results = postproc::read_results(results_dir);
    postproc::Summary summary = postproc::summarize(results);
    if (!no_pictures) {
      std::unique_ptr<VirtualDisplay> display;
      if (!std::getenv("DISPLAY") || !*std::getenv("DISPLAY")) display = std::make_unique<VirtualDisplay>();
      ro.times = times;
      auto direction = [](const std::vector<double>& d, const char* option) -> std::optional<Vec3> {
        if (d.empty()) return std::nullopt;
        if (!std::all_of(d.begin(), d.end(), [](double x) { return std::isfinite(x); }) || std::hypot(d[0], d[1], d[2]) == 0)
          throw InputError("command line", option, "a non-zero direction x y z");
        return Vec3{d[0], d[1], d[2]};
      };
      ro.view = direction(view, "--view");
      ro.section_normal = direction(section_normal, "--section-normal");
      summary.pictures = postproc::render_report(results, summary, staged.path(), ro);
    }
    const postproc::WebReport web = postproc::write_web_report(results, summary, staged.path(), wo);
    if (!no_html) {
      summary.interactive = "index.html";
      log::info() << "interactive report: " << web.files.size() << " files, " << std::fixed << std::setprecision(1)
                  << static_cast<double>(web.bytes) / (1 << 20) << " MB, " << web.faces_shown << " of " << web.surface_faces << " surface triangles";
      for (const std::string& m : web.missing) log::warn("interactive report: not shown: " + m);
    }
    write_file(staged.path() / "summary.json", postproc::summary_json(summary));
    write_file(staged.path() / "summary.md", postproc::summary_markdown(summary));
    staged.commit();
    log::info() << "report: " << (out / "summary.md").string() << " (" << summary.pictures.size() << " pictures)";
  });
}
