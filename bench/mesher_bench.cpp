// Mesher benchmark on the default-resolution phantom's labels: the paper-size hand mesh
// (default criteria) and a fine mesh (--fine: >= 300k tets), with time, peak memory and quality.
// Labels: the segmentation of the phantom's CT (what the pipeline meshes; default) or its truth.
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>

#include "tactus/core/cli.hpp"
#include "tactus/core/stable_step.hpp"
#include "tactus/data_samples/phantom.hpp"
#include "tactus/mesher/image_mesher.hpp"
#include "tactus/mesher/quality.hpp"
#include "tactus/segment/segment.hpp"

int main(int argc, char** argv) {
  using namespace tactus;
  CLI::App app{"tactus-bench-mesher: CGAL meshing time, memory and quality on the phantom", "tactus-bench-mesher"};
  cli::CommonOptions common;
  cli::add_common_options(app, common, "");
  bool fine = false;
  app.add_flag("--fine", fine, "also mesh with criteria giving >= 300k tets");
  std::string source = "segmented";
  app.add_option("--labels", source, "segmented | truth")->check(CLI::IsMember({"segmented", "truth"}))->capture_default_str();
  return cli::run(app, argc, argv, common, [&] {
    const auto ph = samples::make_hand_phantom(samples::PhantomParams{});
    Volume<std::uint8_t> labels = ph.truth;
    LabelTable table = ph.labels;
    if (source == "segmented") {
      Volume<float> hu;
      hu.dims = ph.ct.dims, hu.spacing = ph.ct.spacing, hu.origin = ph.ct.origin;
      hu.data.assign(ph.ct.data.begin(), ph.ct.data.end());
      auto seg = segment::segment_hand(hu, segment::SegmentParams{});
      labels = std::move(seg.labels), table = std::move(seg.table);
    }
    std::vector<std::pair<std::string, mesher::ImageMeshParams>> cases{{"paper-size", {}}};
    if (fine) {
      mesher::ImageMeshParams f;
      f.facet_size_mm = 1.6, f.bone_facet_size_mm = 1.2, f.facet_distance_mm = 0.25, f.cell_size_mm = 2.0, f.bone_cell_size_mm = 1.4;
      cases.emplace_back("fine", f);
    }
    for (const auto& [name, p] : cases) {
      const auto t0 = std::chrono::steady_clock::now();
      const TetMesh m = mesher::mesh_label_volume(labels, table, p);
      const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      // The paper's materials: soft tissue hgo (k = 1e8 Pa, c1), bone E = 10 GPa, nu = 0.22.
      std::map<int, double> speeds;
      for (const auto& g : m.groups)
        if (g.dim == 3)
          speeds[g.tag] = g.tag == 1 ? dilatational_wave_speed(1.0e8, 2 * 10206.9, 1050)
                                     : dilatational_wave_speed(10e9 / (3 * (1 - 2 * 0.22)), 10e9 / (2 * 1.22), 2150);
      const auto q = mesher::quality_report(m, speeds);
      rusage ru{};
      getrusage(RUSAGE_SELF, &ru);
      double worst_bone = 1;
      for (const auto& [group, g] : q["groups"].items())
        if (group != "soft_tissue") worst_bone = std::min(worst_bone, g["min_over_median_length"].get<double>());
      std::printf(
          "%s (%s labels): %zu tets, %zu nodes in %.1f s, peak memory %.0f MB; min dihedral %.2f deg, %.3f %% below 10 deg; "
          "L_e min/median per subdomain: soft tissue %.3f, worst bone %.3f; critical step %.3g s\n",
          name.c_str(), source.c_str(), m.tets.size(), m.nodes.size(), t, static_cast<double>(ru.ru_maxrss) / 1024.0,
          q["all"]["min_dihedral_deg"].get<double>(), 100 * q["all"]["fraction_min_dihedral_below_10deg"].get<double>(),
          q["groups"]["soft_tissue"]["min_over_median_length"].get<double>(), worst_bone, q["critical_time_step"]["dt_s"].get<double>());
      std::fflush(stdout);
    }
  });
}
