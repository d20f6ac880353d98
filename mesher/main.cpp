// tactus-mesh: labels.h5 -> conforming multi-material tet mesh (CGAL Mesh_3), and object meshes
// with gmsh (`box`, `stl`). Writes mesh.msh (gmsh 4.1), mesh.vtu and quality.json. `fibres`
// writes rule-based hgo fibre directions of a mesh as the .vtu that bodies.fibres reads;
// `skeleton` the hand's bones, parents and joints of a mesh as skeleton.json.
#include <charconv>
#include <chrono>
#include <cmath>
#include <fstream>
#include <memory>
#include <sstream>
#include <type_traits>

#include "tactus/core/cli.hpp"
#include "tactus/core/error.hpp"
#include "tactus/core/file_io.hpp"
#include "tactus/core/log.hpp"
#include "tactus/core/output.hpp"
#include "tactus/core/stable_step.hpp"
#include "tactus/mesher/fibres.hpp"
#include "tactus/mesher/image_mesher.hpp"
#include "tactus/mesher/objects.hpp"
#include "tactus/mesher/quality.hpp"
#include "tactus/mesher/skeleton.hpp"
#include "tactus/mesher/small_regions.hpp"
#include "tactus/mesher/thickness.hpp"
#include "tactus/mesher/well_composed.hpp"

namespace {

using namespace tactus;

// The output files of a mesh: <out>/mesh.msh, mesh.vtu, quality.json for a folder output, or
// <out>.msh, <out>.vtu, <out>_quality.json when -o names a .msh file.
std::vector<std::filesystem::path> output_files(const std::filesystem::path& out) {
  if (out.extension() != ".msh") return {out / "mesh.msh", out / "mesh.vtu", out / "quality.json"};
  const std::filesystem::path base = out.parent_path() / out.stem();
  return {out, base.string() + ".vtu", base.string() + "_quality.json"};
}

// Writes the mesh, its .vtu and the quality report into the staged output and commits it.
template <class Output>
void write_outputs(const tactus::TetMesh& mesh, Output& out, std::size_t first, const std::map<int, double>& speeds, const nlohmann::json& extra,
                   const tactus::mesher::QualityAdvice& advice) {
  const auto path = [&](std::size_t i) {
    if constexpr (std::is_same_v<Output, tactus::OutputFiles>)
      return out.staged(first + i);
    else
      return out.path() / std::vector<std::string>{"mesh.msh", "mesh.vtu", "quality.json"}[i];
  };
  tactus::write_msh(path(0), mesh);
  tactus::write_vtu(path(1), mesh);
  auto report = tactus::mesher::quality_report(mesh, speeds, 10.0, {}, advice);
  for (const auto& [key, value] : extra.items()) report[key] = value;
  tactus::write_file(path(2), report.dump(2) + '\n');
  out.commit();
  const auto& all = report["all"];
  std::ostringstream step;
  if (report.contains("critical_time_step"))
    step << "; critical step " << report["critical_time_step"]["dt_s"].get<double>() << " s (tet "
         << report["critical_time_step"]["element"].get<long>() << " in " << report["critical_time_step"]["group"].get<std::string>()
         << ", L_e min/median " << all["min_over_median_length"].get<double>() << ")";
  tactus::log::info() << "mesh: " << mesh.nodes.size() << " nodes, " << mesh.tets.size() << " tets; min dihedral "
                      << all["min_dihedral_deg"].get<double>() << " deg, " << 100 * all["fraction_min_dihedral_below_10deg"].get<double>()
                      << " % of tets below 10 deg" << step.str();
  nlohmann::json unmet = report["guarantees"]["unmet"];
  for (const auto& u : report["guarantees"]["boundary_manifold"]["unmet"]) unmet.push_back(u);
  for (const auto& u : unmet) {
    std::ostringstream o;
    o << "mesh: guarantee " << u["guarantee"].get<std::string>() << " not met in " << u["group"].get<std::string>() << ": "
      << u["value"].get<double>();
    if (u.contains("element"))
      o << " at tet " << u["element"].get<long>() << " (" << u["tets_below"].get<long>() << " tets below)";
    else
      o << " near (" << u["at_m"][0].get<double>() << ", " << u["at_m"][1].get<double>() << ", " << u["at_m"][2].get<double>() << ") m";
    o << "; " << u["why"].get<std::string>() << " (quality.json \"guarantees\")";
    tactus::log::warn(o.str());
  }
}

// The P-wave speed of every volume group from --wave-speed GROUP=SPEED arguments ("*" for the
// rest); 1000 m/s everywhere when none is given (the report says so).
std::map<int, double> wave_speeds(const tactus::TetMesh& mesh, const std::vector<std::string>& args) {
  std::map<std::string, double> by_name;
  for (const auto& a : args) {
    const auto eq = a.find('=');
    double v = 0;
    const char* first = eq == std::string::npos ? nullptr : a.data() + eq + 1;
    const auto [end, ec] = first ? std::from_chars(first, a.data() + a.size(), v) : std::from_chars_result{nullptr, std::errc::invalid_argument};
    if (eq == std::string::npos || ec != std::errc() || end != a.data() + a.size() || !(v > 0) || !std::isfinite(v))
      throw tactus::InputError("command line", "--wave-speed", "GROUP=SPEED with a speed > 0 in m/s", "\"" + a + "\"");
    by_name[a.substr(0, eq)] = v;
  }
  std::map<int, double> speeds;
  for (const auto& g : mesh.groups) {
    if (g.dim != 3) continue;
    auto it = by_name.find(g.name);
    if (it == by_name.end()) it = by_name.find("*");
    speeds[g.tag] = it != by_name.end() ? it->second : (args.empty() ? 1000.0 : 0.0);
  }
  for (const auto& [name, v] : by_name)
    if (name != "*" && !mesh.find_group(3, name))
      throw tactus::InputError("command line", "--wave-speed", "a volume group of the mesh", "\"" + name + "\"");
  return speeds;
}

// A folder output, or the three files next to a .msh path.
struct MeshOutput {
  std::unique_ptr<tactus::OutputFolder> folder;
  std::unique_ptr<tactus::OutputFiles> files;
  MeshOutput(const std::filesystem::path& out, const tactus::OutputRules& rules) {
    if (out.extension() == ".msh")
      files = std::make_unique<tactus::OutputFiles>(output_files(out), rules);
    else
      folder = std::make_unique<tactus::OutputFolder>(out, rules);
  }
  // advice: what an unmet guarantee's message suggests (the image mesher's options by default).
  void write(const tactus::TetMesh& mesh, const std::map<int, double>& speeds, const nlohmann::json& extra = nlohmann::json::object(),
             const tactus::mesher::QualityAdvice& advice = {}) {
    if (files)
      write_outputs(mesh, *files, 0, speeds, extra, advice);
    else
      write_outputs(mesh, *folder, 0, speeds, extra, advice);
  }
};

// tactus-mesh fibres: the rule-based field of fibres.hpp, written next to nothing else: -o FILE.vtu
// (or a folder: FOLDER/fibres.vtu), with the cell data fibre_1, fibre_2 the solver reads and, for
// pictures, fibre_direction, skin_normal, skin_distance and the point potential fibre_phi.
void write_fibres(const std::filesystem::path& mesh_file, const tactus::mesher::FibreFieldOptions& options, const std::filesystem::path& out,
                  const tactus::OutputRules& rules) {
  using namespace tactus;
  const std::filesystem::path file = out.extension() == ".vtu" ? out : out / "fibres.vtu";
  OutputFiles files({file}, rules);
  const TetMesh mesh = read_msh(mesh_file);
  const mesher::FibreField f = mesher::rule_based_fibres(mesh, options, mesh_file.string());
  auto cells = [](const char* name, const std::vector<Vec3>& v) {
    MeshField m{name, 3, {}};
    for (const Vec3& x : v) m.values.insert(m.values.end(), x.begin(), x.end());
    return m;
  };
  write_vtu(files.staged(0), mesh, {MeshField{"fibre_phi", 1, f.phi}},
            {cells("fibre_1", f.fibre_1), cells("fibre_2", f.fibre_2), cells("fibre_direction", f.direction), cells("skin_normal", f.skin_normal),
             MeshField{"skin_distance", 1, f.skin_distance}});
  files.commit();
  log::info() << "wrote " << file.string();
}

// The options of meshing a label volume (the tool's main job).
struct ImageOptions {
  std::string labels_file;
  mesher::ImageMeshParams p;
  // The materials are the solver's business: the report quotes the critical step for the wave
  // speeds given here (per physical volume name, "*" for the others), and otherwise the step
  // each subdomain would have at 1000 m/s, which scales as 1 / speed.
  std::vector<std::string> speed_args;
  std::vector<double> refine_box_mm;
  bool keep_surfaces = false, keep_small_regions = false;
  double min_region_mm3 = 0;
  double joint_space_mm = 0;
  double min_thickness_mm = 0;
};

void add_image_options(CLI::App& app, ImageOptions& o) {
  mesher::ImageMeshParams& p = o.p;
  app.add_option("labels", o.labels_file, "labels.h5 from tactus-segment");
  app.add_option("--facet-angle", p.facet_angle_deg, "min surface triangle angle, deg")->capture_default_str();
  app.add_option("--facet-size", p.facet_size_mm, "max surface triangle size, mm")->capture_default_str();
  app.add_option("--bone-facet-size", p.bone_facet_size_mm, "max triangle size on bone surfaces, mm")->capture_default_str();
  app.add_option("--facet-distance", p.facet_distance_mm, "surface approximation error, mm")->capture_default_str();
  app.add_option("--smooth-boundaries", p.boundary_smoothing_voxels,
                 "Gaussian sigma (voxels, 0-3) of the label indicators: boundaries between voxel centres instead of the voxels' staircase "
                 "(0: off)")
      ->capture_default_str();
  app.add_option("--refine-box", o.refine_box_mm,
                 "X0 Y0 Z0 X1 Y1 Z1: a world box (mm) meshed finer, e.g. where the skin will touch (with --refine-size)")
      ->expected(6);
  app.add_option("--refine-joints", p.refine_joints_mm,
                 "D: also refine (at --refine-size) everything within D mm of two different bones - the joints' gaps and creases, "
                 "where flexing squeezes the tissue")
      ->check(CLI::PositiveNumber);
  app.add_option("--refine-size", p.refine_size_mm, "max facet size inside --refine-box and --refine-joints, mm (cells there: twice it)")
      ->check(CLI::PositiveNumber);
  app.add_option("--refine-distance", p.refine_distance_mm, "surface approximation error inside --refine-box, mm (default: --facet-distance)")
      ->check(CLI::PositiveNumber);
  app.add_option("--radius-edge", p.cell_radius_edge, "max cell radius-edge ratio")->capture_default_str();
  app.add_option("--cell-size", p.cell_size_mm, "soft-tissue cell size, mm")->capture_default_str();
  app.add_option("--bone-cell-size", p.bone_cell_size_mm, "bone cell size, mm")->capture_default_str();
  app.add_flag("--odt", p.odt, "ODT smoothing before perturb/exude");
  app.add_flag("--lloyd", p.lloyd, "Lloyd smoothing before perturb/exude");
  app.add_option("--sliver-bound", p.exude_sliver_bound_deg, "perturb/exude target dihedral angle, deg")->capture_default_str();
  app.add_option("--time-limit", p.optimiser_time_limit_s, "time limit of each optimiser, s")->capture_default_str();
  app.add_flag("--no-volume-restore", o.keep_surfaces, "keep CGAL's surfaces (bones then come out 3-4 % small)");
  app.add_option("--min-region-mm3", o.min_region_mm3,
                 "connected regions of one label (or enclosed background pockets) smaller than this go to the label they border most "
                 "(0: two tets of the bone cell size, bone-cell-size^3 / 5)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--min-thickness-mm", o.min_thickness_mm,
                 "T: the parts of a label where no ball of diameter T fits go to the neighbouring label they share the most faces with "
                 "(a gap or fin thinner than T; 0: none - a label thinner than its cells is then meshed finer instead)")
      ->check(CLI::NonNegativeNumber);
  app.add_flag("--keep-small-regions", o.keep_small_regions, "mesh every region however small (tiny tets set the stable step)");
  app.add_option("--joint-space", o.joint_space_mm,
                 "D: leave the soft tissue within D mm of two different bones unmeshed - the joints' spaces, where cartilage slides "
                 "rather than binds the bones (at most half the joints' gaps wider than it; 0: off)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--seed", p.seed, "random seed")->capture_default_str();
  app.add_option("--max-elements", p.max_elements, "refuse meshes expected to have more tets than this")->capture_default_str();
  app.add_option("--wave-speed", o.speed_args,
                 "GROUP=SPEED: P-wave speed (m/s) of a physical volume for the step report "
                 "(repeatable; GROUP \"*\" for the rest; e.g. soft_tissue=309 \"*\"=2304, the paper's tissue and bone)");
}

// Regions below --min-region-mm3 given to the label they border most, each warned about; what
// the report lists of them.
nlohmann::json absorb_small_regions(Volume<std::uint8_t>& labels, const LabelTable& table, const ImageOptions& o) {
  nlohmann::json absorbed = nlohmann::json::array();
  const std::size_t min_voxels = mesher::min_region_voxels(labels, o.min_region_mm3, o.p.bone_cell_size_mm);
  for (const auto& r : mesher::absorb_small_regions(labels, min_voxels)) {
    const auto name = [&](int id) { return label_name(table, id); };
    std::ostringstream m;
    m << "mesher: a region of " << name(r.label) << " of " << r.voxels << " voxel(s) at (" << r.at[0] << ", " << r.at[1] << ", " << r.at[2]
      << ") m is below " << min_voxels << " voxels (--min-region-mm3); it becomes " << name(r.into);
    log::warn(m.str());
    absorbed.push_back({{"label", r.label}, {"name", name(r.label)}, {"voxels", r.voxels}, {"into", r.into}, {"at_m", r.at}});
  }
  return absorbed;
}

// The label configurations that touch only along a voxel edge or at a corner, resolved
// (well_composed.hpp); what the report lists of them.
nlohmann::json make_labels_well_composed(Volume<std::uint8_t>& labels) {
  const mesher::WellComposedReport r = mesher::make_well_composed(labels);
  if (r.voxels_changed > 0)
    log::info() << "mesher: " << r.edge_pinches << " edge and " << r.vertex_pinches << " vertex pinch(es) of the labels resolved by changing "
                << r.voxels_changed << " voxel(s) (" << static_cast<double>(r.voxels_changed) * labels.voxel_volume() * 1e9 << " mm^3)"
                << (r.remaining ? "; " + std::to_string(r.remaining) + " left" : std::string());
  nlohmann::json changes = nlohmann::json::array();
  for (const auto& c : r.changes) changes.push_back({{"voxel", c.voxel}, {"from", c.from}, {"to", c.to}});
  return {{"edge_pinches", r.edge_pinches},     {"vertex_pinches", r.vertex_pinches},
          {"voxels_changed", r.voxels_changed}, {"volume_moved_m3", static_cast<double>(r.voxels_changed) * labels.voxel_volume()},
          {"remaining", r.remaining},           {"changes", changes}};
}

void mesh_labels(ImageOptions o, const cli::CommonOptions& common) {
  if (o.labels_file.empty()) throw CLI::RequiredError("labels");
  MeshOutput output(common.output, common.output_rules({o.labels_file}));
  mesher::ImageMeshParams& p = o.p;
  p.restore_volumes = !o.keep_surfaces;
  if (!o.refine_box_mm.empty() && !(p.refine_size_mm > 0)) throw InputError("command line", "--refine-box", "a --refine-size for the box", "none");
  if (p.refine_joints_mm > 0 && !(p.refine_size_mm > 0))
    throw InputError("command line", "--refine-joints", "a --refine-size for the joints", "none");
  if (p.refine_size_mm > 0 && o.refine_box_mm.empty() && !(p.refine_joints_mm > 0))
    throw InputError("command line", "--refine-size", "a --refine-box or --refine-joints to refine", "none");
  for (std::size_t i = 0; i < o.refine_box_mm.size(); ++i) p.refine_box_m[i] = o.refine_box_mm[i] * 1e-3;
  p.refine_cell_size_mm = 2 * p.refine_size_mm;  // the box's cells grade inward from its finer surface
  LabelTable table;
  auto labels = read_h5<std::uint8_t>(o.labels_file, "/labels", &table);
  const nlohmann::json absorbed = o.keep_small_regions ? nlohmann::json::array() : absorb_small_regions(labels, table, o);
  const nlohmann::json thin = mesher::fit_thin_labels(labels, table, o.p, o.min_thickness_mm, o.labels_file);
  const nlohmann::json well_composed = make_labels_well_composed(labels);
  std::size_t carved = 0;  // --joint-space: the soft tissue between two bones becomes a cavity
  if (o.joint_space_mm > 0) {
    const std::vector<std::uint8_t> space = mesher::joint_gap_mask(labels, o.joint_space_mm);
    for (std::size_t v = 0; v < labels.size(); ++v)
      if (space[v] && labels.data[v] == contracts::kSoftTissueLabel) labels.data[v] = 0, ++carved;
    log::info() << "joint spaces: " << carved << " soft-tissue voxels within " << o.joint_space_mm << " mm of two bones left unmeshed ("
                << static_cast<double>(carved) * labels.voxel_volume() * 1e9 << " mm^3)";
  }
  const auto t0 = std::chrono::steady_clock::now();
  mesher::ImageMeshReport report;
  const TetMesh mesh = mesher::mesh_label_volume(labels, table, p, &report);
  log::info() << "meshed in " << std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() << " s";
  const mesher::BoundaryPinchReport& pinches = report.pinches;
  const nlohmann::json boundary_pinches = {{"manifold_criterion_capped", report.manifold_criterion_capped},
                                           {"defects_before", pinches.defects_before},
                                           {"tets_relabelled", pinches.tets_relabelled},
                                           {"tets_removed", pinches.tets_removed},
                                           {"volume_moved_m3", pinches.volume_moved_m3},
                                           {"defects_after", pinches.defects_after}};
  output.write(mesh, wave_speeds(mesh, o.speed_args),
               {{"absorbed_regions", absorbed},
                {"joint_space_voxels", carved},
                {"well_composed", well_composed},
                {"thin_regions", thin},
                {"boundary_pinches", boundary_pinches}});
}

// skeleton.json of a hand mesh's bone groups.
void write_skeleton_of(const std::filesystem::path& mesh_file, const std::string& names_file, double gap_mm, const std::filesystem::path& out,
                       const tactus::OutputRules& rules) {
  using namespace tactus;
  if (!(gap_mm > 0 && gap_mm <= 50)) throw InputError("command line", "--neighbour-gap", "a gap from 0 to 50 mm", std::to_string(gap_mm));
  const std::filesystem::path file = out.extension() == ".json" ? out : out / "skeleton.json";
  OutputFiles files({file}, rules);
  mesher::SkeletonOptions options;
  options.neighbour_gap_m = gap_mm * 1e-3;
  options.source = mesh_file.string();
  if (!names_file.empty()) options.names = mesher::read_bone_names(names_file);
  const Skeleton skeleton = mesher::extract_skeleton(read_msh(mesh_file), options);
  write_skeleton(files.staged(0), skeleton);
  files.commit();
  log::info() << "wrote " << file.string();
}

// The subcommands: the paper's block and an STL object (gmsh), the fibre field and the skeleton of a mesh.
struct ObjectTools {
  CLI::App *box, *fibres, *stl, *skeleton, *cylinder;
  std::array<double, 3> size{0.1, 0.1, 0.05}, origin{0, 0, 0};
  double h = 0.01, edge_radius = 0, stl_scale = 1.0;
  std::string fib_mesh, fib_axis = "z", stl_file, skeleton_mesh, names_file;
  double neighbour_gap_mm = 3.5;
  mesher::FibreFieldOptions fo;
  mesher::CylinderSpec cyl;
  std::string cyl_axis = "x";

  explicit ObjectTools(CLI::App& app)
      : box(app.add_subcommand("box", "the paper's parallelepiped block, meshed with gmsh")),
        fibres(app.add_subcommand("fibres", "rule-based hgo fibre directions of a mesh, as the .vtu bodies.fibres reads")),
        stl(app.add_subcommand("stl", "a closed STL object, meshed with gmsh")),
        skeleton(app.add_subcommand("skeleton", "the bones, their parents and the joints (centre, flexion and abduction axes) of a hand mesh")),
        cylinder(app.add_subcommand("cylinder", "a cylinder (a tool handle), optionally a deformable sleeve over a core, meshed with gmsh")) {
    box->add_option("--size", size, "edge lengths, m")->capture_default_str();
    box->add_option("--origin", origin, "lower corner, m")->capture_default_str();
    box->add_option("--element-size", h, "element size, m")->capture_default_str();
    box->add_option("--edge-radius", edge_radius, "round every edge with this radius, m (meshed at about half of it; 0: sharp)")
        ->capture_default_str();
    fibres->add_option("mesh", fib_mesh, "the mesh (.msh) with a skin surface group")->required();
    fibres->add_option("--angle", fo.angle_deg, "each family's angle to the reference direction, deg")->capture_default_str();
    fibres->add_option("--axis", fib_axis, "x, y or z: the base (the wrist) is the mesh's low end along it")->capture_default_str();
    fibres->add_option("--base-fraction", fo.base_fraction, "nodes within this fraction of the extent from the low end form the base")
        ->capture_default_str();
    fibres->add_option("--skin-group", fo.skin_group, "the physical surface group of the skin")->capture_default_str();
    stl->add_option("file", stl_file, "closed STL surface")->required();
    stl->add_option("--element-size", h, "element size, m")->capture_default_str();
    stl->add_option("--scale", stl_scale, "factor from STL units to m (1e-3 for mm)")->capture_default_str();
    cylinder->add_option("--radius", cyl.radius, "outer radius, m")->capture_default_str();
    cylinder->add_option("--length", cyl.length, "length along the axis, m")->capture_default_str();
    cylinder->add_option("--axis", cyl_axis, "x, y or z")->capture_default_str();
    cylinder->add_option("--centre", cyl.centre, "centre, m")->capture_default_str();
    cylinder
        ->add_option("--sleeve", cyl.sleeve, "thickness of a sleeve over a core, m: volume groups \"core\" and \"sleeve\" (0: one volume \"object\")")
        ->capture_default_str();
    cylinder->add_option("--element-size", cyl.element_size, "element size, m (the sleeve: at most half its thickness)")->capture_default_str();
    skeleton->add_option("mesh", skeleton_mesh, "the hand mesh (.msh) whose volume groups 2.. are bones")->required();
    skeleton->add_option("--names", names_file, "a JSON file {\"labels\": {\"<label>\": \"<bone name>\"}} naming the bones");
    skeleton->add_option("--neighbour-gap", neighbour_gap_mm, "bones whose surfaces come this close are neighbours, mm")->capture_default_str();
  }

  // False when no subcommand was given (a label volume is to be meshed).
  bool run(const ImageOptions& o, const cli::CommonOptions& common) const {
    const std::filesystem::path out = common.output;
    if (fibres->parsed()) {
      if (fib_axis != "x" && fib_axis != "y" && fib_axis != "z") throw InputError("command line", "--axis", "x, y or z", "\"" + fib_axis + "\"");
      mesher::FibreFieldOptions options = fo;
      options.axis = fib_axis[0] - 'x';
      write_fibres(fib_mesh, options, out, common.output_rules({fib_mesh}));
    } else if (skeleton->parsed()) {
      std::vector<std::filesystem::path> inputs{skeleton_mesh};
      if (!names_file.empty()) inputs.push_back(names_file);
      write_skeleton_of(skeleton_mesh, names_file, neighbour_gap_mm, out, common.output_rules(inputs));
    } else if (box->parsed()) {
      MeshOutput output(out, common.output_rules({}));
      const TetMesh mesh = mesher::mesh_box(size, origin, h, "block", o.p.max_elements, edge_radius);
      output.write(mesh, wave_speeds(mesh, o.speed_args), nlohmann::json::object(), mesher::QualityAdvice::gmsh_object());
    } else if (cylinder->parsed()) {
      if (cyl_axis != "x" && cyl_axis != "y" && cyl_axis != "z") throw InputError("command line", "--axis", "x, y or z", "\"" + cyl_axis + "\"");
      MeshOutput output(out, common.output_rules({}));
      mesher::CylinderSpec spec = cyl;
      spec.axis = cyl_axis[0] - 'x';
      const TetMesh mesh = mesher::mesh_cylinder(spec, o.p.max_elements);
      output.write(mesh, wave_speeds(mesh, o.speed_args), nlohmann::json::object(), mesher::QualityAdvice::gmsh_object());
    } else if (stl->parsed()) {
      MeshOutput output(out, common.output_rules({stl_file}));
      const TetMesh mesh = mesher::mesh_stl_object(stl_file, h, stl_scale, "object", o.p.max_elements);
      output.write(mesh, wave_speeds(mesh, o.speed_args), nlohmann::json::object(), mesher::QualityAdvice::gmsh_object());
    } else {
      return false;
    }
    return true;
  }
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"tactus-mesh: conforming tetrahedral meshes of segmented anatomy (CGAL) and of objects (gmsh)", "tactus-mesh"};
  cli::CommonOptions common;
  cli::add_common_options(app, common, "output folder, or a .msh path", "an output folder or .msh path");
  ImageOptions options;
  add_image_options(app, options);
  app.fallthrough();  // -o, -v given after a subcommand belong to the main command
  const ObjectTools tools(app);
  return cli::run(app, argc, argv, common, [&] {
    if (!tools.run(options, common)) mesh_labels(options, common);
  });
}
