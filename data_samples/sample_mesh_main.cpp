// tactus-sample-mesh: a structured tet box (6 tets per cell) with an optional second material
// ("bone") where tet centroids fall inside a box: the sample mesh of the solver's bundled
// scenario. Meshes of segmented anatomy come from the mesher stage (tactus-mesh).
#include <cmath>

#include "tactus/core/cli.hpp"
#include "tactus/core/error.hpp"
#include "tactus/core/output.hpp"
#include "tactus/data_samples/box_mesh.hpp"

int main(int argc, char** argv) {
  using namespace tactus;
  CLI::App app{"tactus-sample-mesh: structured tetrahedral box mesh (.msh)", "tactus-sample-mesh"};
  cli::CommonOptions common;
  cli::add_common_options(app, common, "output .msh file", "an output .msh path");
  std::array<double, 3> size{0.1, 0.1, 0.1}, origin{0, 0, 0};
  std::array<int, 3> cells{10, 10, 10};
  std::vector<double> inclusion;
  app.add_option("--size", size, "box edge lengths in m");
  app.add_option("--origin", origin, "lower corner in m");
  app.add_option("--cells", cells, "cells along x, y, z");
  app.add_option("--inclusion", inclusion, "xmin ymin zmin xmax ymax zmax: tets inside become group 'bone'")->expected(6);
  return cli::run(app, argc, argv, common, [&] {
    double tets = 6;
    for (int c = 0; c < 3; ++c) {
      if (!(size[c] > 0) || !std::isfinite(size[c]) || size[c] > 1e3) throw InputError("command line", "--size", "lengths from 0 to 1000 m");
      if (!std::isfinite(origin[c]) || std::abs(origin[c]) > 1e3) throw InputError("command line", "--origin", "a finite corner within 1 km");
      if (cells[c] < 1) throw InputError("command line", "--cells", "at least one cell per axis");
      tets *= cells[c];
    }
    if (tets > 5e7) throw InputError("command line", "--cells", "at most 50 million tets (6 per cell)", std::to_string(static_cast<long long>(tets)));
    TetMesh m = samples::make_box_mesh(cells[0], cells[1], cells[2], size[0], size[1], size[2], origin);
    if (!inclusion.empty()) {
      m.groups.push_back({3, 2, "bone"});
      for (std::size_t e = 0; e < m.tets.size(); ++e) {
        Vec3 c{0, 0, 0};
        for (int v : m.tets[e])
          for (int k = 0; k < 3; ++k) c[k] += m.nodes[v][k] / 4;
        bool in = true;
        for (int k = 0; k < 3; ++k) in = in && c[k] >= inclusion[k] && c[k] <= inclusion[3 + k];
        if (in) m.tet_group[e] = 2;
      }
      m.groups[0].name = "soft_tissue";
    }
    OutputFiles out({common.output}, common.output_rules({}));
    write_msh(out.staged(0), m);
    out.commit();
  });
}
