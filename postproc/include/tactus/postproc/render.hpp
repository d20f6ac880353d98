#pragma once
// The report's pictures, rendered off screen with VTK (an X display is needed: tactus-post
// starts a private Xvfb when none is set).
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "tactus/core/vec3.hpp"
#include "tactus/postproc/results.hpp"
#include "tactus/postproc/summary.hpp"

namespace tactus::postproc {

// The views are chosen from the data, whatever the bodies: the stress pictures look along the
// model's axis of least extent (its principal axes), with the longest axis up; the section is
// normal to the longest axis of the body carrying the contact pressure, through the peak pressure;
// the pressure map shows that body from the side its contact faces (its pressure-weighted surface
// normal). Each can be overridden.
struct RenderOptions {
  std::vector<double> times;  // states to draw (nearest output); empty: every output state
  int width = 1200, height = 900;
  std::string pressure_body;           // body the pressure map shows (default: the one with the highest pressure)
  std::optional<Vec3> view;            // direction from the model to the camera of the stress pictures
  std::optional<Vec3> section_normal;  // normal of the section plane
};

// Writes into `report`: von_mises_t<ms>.png per chosen time (deformed bodies, one fixed colour
// scale), section.png (materials and von Mises on a section through the peak pressure),
// pressure.png (the contact pressure on its body at the state with the highest pressure, peak
// marked), plot_*.png (time histories). Returns the file names written.
// The colour scale's top for contact pressure: the area-weighted 99.5th percentile of the pressed
// nodes' (pressure, area) pairs - the smallest pressure with 99.5 % of the pressed area at or
// below it - so that one hot node does not turn the rest of a map blue (the true peak keeps its
// black dot and its value in the caption). 0 when nothing is pressed.
double pressure_scale_cap(std::vector<std::pair<double, double>> pressure_area);

std::vector<std::string> render_report(const Results& results, const Summary& summary, const std::filesystem::path& report,
                                       const RenderOptions& options);

}  // namespace tactus::postproc
