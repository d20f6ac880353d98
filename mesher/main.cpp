// tactus-mesh: labels.h5 -> conforming multi-material tet mesh (CGAL Mesh_3), and object meshes
// with gmsh (`box`, `stl`). Writes mesh.msh (gmsh 4.1), mesh.vtu and quality.json.
#include <chrono>
#include <fstream>
#include <sstream>

#include "tactus/core/cli.hpp"
#include "tactus/core/error.hpp"
#include "tactus/core/log.hpp"
#include "tactus/core/staged_output.hpp"
#include "tactus/core/stable_step.hpp"
#include "tactus/mesher/image_mesher.hpp"
#include "tactus/mesher/objects.hpp"
#include "tactus/mesher/quality.hpp"

namespace {

// Writes <out>.msh, <out>.vtu and <out>_quality.json (or quality.json in a folder output).
void write_outputs(const tactus::TetMesh& mesh, const std::filesystem::path& out, const std::map<int, double>& speeds) {
  namespace fs = std::filesystem;
  const fs::path msh = out.extension() == ".msh" ? out : out / "mesh.msh";
  const fs::path base = msh.parent_path() / msh.stem();
  tactus::write_msh(msh, mesh);
  tactus::write_vtu(fs::path(base.string() + ".vtu"), mesh);
  const auto report = tactus::mesher::quality_report(mesh, speeds);
  const fs::path q = out.extension() == ".msh" ? fs::path(base.string() + "_quality.json") : out / "quality.json";
  tactus::StagedOutput staged(q);
  std::ofstream(staged.path()) << report.dump(2) << '\n';
  staged.commit();
  const auto& all = report["all"];
  std::ostringstream step;
  if (report.contains("critical_time_step"))
    step << "; critical step " << report["critical_time_step"]["dt_s"].get<double>() << " s (tet "
         << report["critical_time_step"]["element"].get<long>() << " in " << report["critical_time_step"]["group"].get<std::string>()
         << ", L_e min/median " << all["min_over_median_length"].get<double>() << ")";
  tactus::log::info() << "mesh: " << mesh.nodes.size() << " nodes, " << mesh.tets.size() << " tets; min dihedral "
                      << all["min_dihedral_deg"].get<double>() << " deg, "
                      << 100 * all["fraction_min_dihedral_below_10deg"].get<double>() << " % of tets below 10 deg" << step.str()
                      << "; wrote " << msh.string();
}

}  // namespace

int main(int argc, char** argv) {
  using namespace tactus;
  CLI::App app{"tactus-mesh: conforming tetrahedral meshes of segmented anatomy (CGAL) and of objects (gmsh)", "tactus-mesh"};
  cli::CommonOptions common;
  cli::add_common_options(app, common, "output folder, or a .msh path", "an output folder or .msh path");
  std::string labels_file;
  mesher::ImageMeshParams p;
  double soft_speed = dilatational_wave_speed(1.0e8, 2 * 10206.9, 1050);  // paper's hgo tissue
  // P-wave speed of an isotropic elastic solid from E, nu, rho, through core's definition.
  auto elastic_speed = [](double E, double nu, double rho) {
    return dilatational_wave_speed(E / (3 * (1 - 2 * nu)), E / (2 * (1 + nu)), rho);
  };
  double bone_speed = elastic_speed(10e9, 0.22, 2150);  // paper §3.2
  app.add_option("labels", labels_file, "labels.h5 from tactus-segment");
  app.add_option("--facet-angle", p.facet_angle_deg, "min surface triangle angle, deg")->capture_default_str();
  app.add_option("--facet-size", p.facet_size_mm, "max surface triangle size, mm")->capture_default_str();
  app.add_option("--bone-facet-size", p.bone_facet_size_mm, "max triangle size on bone surfaces, mm")->capture_default_str();
  app.add_option("--facet-distance", p.facet_distance_mm, "surface approximation error, mm")->capture_default_str();
  app.add_option("--radius-edge", p.cell_radius_edge, "max cell radius-edge ratio")->capture_default_str();
  app.add_option("--cell-size", p.cell_size_mm, "soft-tissue cell size, mm")->capture_default_str();
  app.add_option("--bone-cell-size", p.bone_cell_size_mm, "bone cell size, mm")->capture_default_str();
  app.add_flag("--odt", p.odt, "ODT smoothing before perturb/exude");
  app.add_flag("--lloyd", p.lloyd, "Lloyd smoothing before perturb/exude");
  app.add_option("--sliver-bound", p.exude_sliver_bound_deg, "perturb/exude target dihedral angle, deg")->capture_default_str();
  app.add_option("--time-limit", p.optimiser_time_limit_s, "time limit of each optimiser, s")->capture_default_str();
  bool keep_surfaces = false;
  app.add_flag("--no-volume-restore", keep_surfaces, "keep CGAL's surfaces (bones then come out 3-4 % small)");
  app.add_option("--seed", p.seed, "random seed")->capture_default_str();
  app.add_option("--soft-wave-speed", soft_speed, "soft-tissue P-wave speed for the step report, m/s")->capture_default_str();
  app.add_option("--bone-wave-speed", bone_speed, "bone P-wave speed for the step report, m/s")->capture_default_str();

  app.fallthrough();  // -o, -v given after a subcommand belong to the main command
  auto* box = app.add_subcommand("box", "the paper's parallelepiped block, meshed with gmsh");
  std::array<double, 3> size{0.1, 0.1, 0.05}, origin{0, 0, 0};
  double h = 0.01, block_speed = elastic_speed(3e9, 0.35, 1200);  // polymer block (contact issue)
  box->add_option("--size", size, "edge lengths, m")->capture_default_str();
  box->add_option("--origin", origin, "lower corner, m")->capture_default_str();
  box->add_option("--element-size", h, "element size, m")->capture_default_str();
  box->add_option("--wave-speed", block_speed, "P-wave speed for the step report, m/s")->capture_default_str();
  auto* stl = app.add_subcommand("stl", "a closed STL object, meshed with gmsh");
  std::string stl_file;
  double stl_scale = 1.0;
  stl->add_option("file", stl_file, "closed STL surface")->required();
  stl->add_option("--element-size", h, "element size, m")->capture_default_str();
  stl->add_option("--scale", stl_scale, "factor from STL units to m (1e-3 for mm)")->capture_default_str();
  stl->add_option("--wave-speed", block_speed, "P-wave speed for the step report, m/s")->capture_default_str();

  return cli::run(app, argc, argv, common, [&] {
    const std::filesystem::path out = common.output;
    if (box->parsed()) {
      write_outputs(mesher::mesh_box(size, origin, h), out, {{1, block_speed}});
      return;
    }
    if (stl->parsed()) {
      write_outputs(mesher::mesh_stl_object(stl_file, h, stl_scale), out, {{1, block_speed}});
      return;
    }
    if (labels_file.empty()) throw CLI::RequiredError("labels");
    p.restore_volumes = !keep_surfaces;
    LabelTable table;
    const auto labels = read_h5<std::uint8_t>(labels_file, "/labels", &table);
    const auto t0 = std::chrono::steady_clock::now();
    const TetMesh mesh = mesher::mesh_label_volume(labels, table, p);
    log::info() << "meshed in " << std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() << " s";
    std::map<int, double> speeds;
    for (const auto& g : mesh.groups)
      if (g.dim == 3) speeds[g.tag] = g.tag == 1 ? soft_speed : bone_speed;
    write_outputs(mesh, out, speeds);
  });
}
