// Mesher benchmark on the default-resolution phantom's labels: the paper-size hand mesh
// (default criteria) and a fine mesh (--fine: >= 300k tets), with time, peak memory and quality.
#include <sys/resource.h>

#include <chrono>
#include <cstdio>

#include "tactus/core/cli.hpp"
#include "tactus/data_samples/phantom.hpp"
#include "tactus/mesher/image_mesher.hpp"
#include "tactus/mesher/quality.hpp"

int main(int argc, char** argv) {
  using namespace tactus;
  CLI::App app{"tactus-bench-mesher: CGAL meshing time, memory and quality on the phantom", "tactus-bench-mesher"};
  cli::CommonOptions common;
  cli::add_common_options(app, common, "");
  bool fine = false;
  app.add_flag("--fine", fine, "also mesh with criteria giving >= 300k tets");
  return cli::run(app, argc, argv, common, [&] {
    const auto ph = samples::make_hand_phantom(samples::PhantomParams{});
    std::vector<std::pair<std::string, mesher::ImageMeshParams>> cases{{"paper-size", {}}};
    if (fine) {
      mesher::ImageMeshParams f;
      f.facet_size_mm = 1.6, f.bone_facet_size_mm = 1.2, f.facet_distance_mm = 0.25, f.cell_size_mm = 2.0, f.bone_cell_size_mm = 1.4;
      cases.emplace_back("fine", f);
    }
    for (const auto& [name, p] : cases) {
      const auto t0 = std::chrono::steady_clock::now();
      const TetMesh m = mesher::mesh_label_volume(ph.truth, ph.labels, p);
      const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      const auto q = mesher::quality_report(m, {});
      rusage ru{};
      getrusage(RUSAGE_SELF, &ru);
      std::printf("%s: %zu tets, %zu nodes in %.1f s, peak memory %.0f MB; min dihedral %.2f deg, %.3f %% below 10 deg, "
                  "L_e min/median %.3f (soft tissue %.3f)\n",
                  name.c_str(), m.tets.size(), m.nodes.size(), t, static_cast<double>(ru.ru_maxrss) / 1024.0,
                  q["all"]["min_dihedral_deg"].get<double>(), 100 * q["all"]["fraction_min_dihedral_below_10deg"].get<double>(),
                  q["all"]["min_over_median_length"].get<double>(), q["groups"]["soft_tissue"]["min_over_median_length"].get<double>());
      std::fflush(stdout);
    }
  });
}
