#pragma once
// The report's pictures, rendered off screen with VTK (an X display is needed: tactus-post
// starts a private Xvfb when none is set).
#include <filesystem>
#include <string>
#include <vector>

#include "tactus/postproc/results.hpp"
#include "tactus/postproc/summary.hpp"

namespace tactus::postproc {

struct RenderOptions {
  std::vector<double> times;  // states to draw (nearest output); empty: every output state
  int width = 1200, height = 900;
};

// Writes into `report`: von_mises_t<ms>.png per chosen time (deformed bodies, one fixed colour
// scale), section.png (cut through the hand at the peak pressure, bone and soft tissue), pressure.png
// (skin pressure at the state with the highest pressure, peak marked), plot_*.png (time histories).
// Returns the file names written.
std::vector<std::string> render_report(const Results& results, const Summary& summary, const std::filesystem::path& report,
                                       const RenderOptions& options);

}  // namespace tactus::postproc
