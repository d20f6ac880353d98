// The state .vtu files and their results.pvd listing (field names from core/contracts.hpp).
#include <algorithm>
#include <fstream>
#include <iomanip>

#include "results.hpp"
#include "tactus/core/contracts.hpp"
#include "tactus/core/error.hpp"
#include "tactus/core/file_io.hpp"
#include "tactus/solver/internal_force.hpp"

namespace fs = std::filesystem;

namespace tactus::solver {

namespace cp = contracts::point;
namespace cc = contracts::cell;

// Cell and point fields of one state, in the input numbering.
// Returns the largest von Mises stress of each material block in this state.
std::vector<double> write_state(const Model& m, const fs::path& file, const std::vector<double>& u, const std::vector<double>& v,
                                const CellRecords& cell_records, const ContactSolver* contact, double time, const GripRegions* regions) {
  std::vector<double> block_peak(m.blocks.size(), 0.0);
  const std::size_t N = m.num_nodes, E = m.num_elements;
  MeshField disp{cp::displacement.name, 3, std::vector<double>(3 * N)}, vel{cp::velocity.name, 3, std::vector<double>(3 * N)};
  std::vector<Vec3> current(N);
  for (std::size_t i = 0; i < N; ++i) {
    const std::size_t k = static_cast<std::size_t>(m.node_of_input[i]);
    for (int c = 0; c < 3; ++c) {
      disp.values[3 * i + c] = u[3 * k + c];
      vel.values[3 * i + c] = v[3 * k + c];
      current[i][c] = m.X[3 * k + c] + u[3 * k + c];
    }
  }
  // The fields move into the lists write_vtu takes (no copy: a state of a 1M-tet model holds
  // about 150 bytes per tet of them, on top of what the VTK writer copies).
  std::vector<MeshField> point_fields;
  point_fields.push_back(std::move(disp)), point_fields.push_back(std::move(vel));
  if (contact && !contact->empty()) {
    // Contact at this time: pressure r_n / A, tangential traction r_t / A, status, gap (docs/design.md).
    ContactSolver::NodeFields c;
    contact->node_fields(c);
    MeshField p{cp::contact_pressure.name, 1, std::vector<double>(N)}, t{cp::contact_traction.name, 3, std::vector<double>(3 * N)},
        st{cp::contact_status.name, 1, std::vector<double>(N)}, g{cp::contact_gap.name, 1, std::vector<double>(N)},
        a{cp::contact_area.name, 1, std::vector<double>(N)};
    for (std::size_t i = 0; i < N; ++i) {
      const std::size_t k = static_cast<std::size_t>(m.node_of_input[i]);
      p.values[i] = c.pressure[k], st.values[i] = c.status[k], g.values[i] = c.gap[k], a.values[i] = c.area[k];
      for (int d = 0; d < 3; ++d) t.values[3 * i + d] = c.traction[3 * k + d];
    }
    for (MeshField* f : {&p, &t, &st, &g, &a}) point_fields.push_back(std::move(*f));
  }
  if (regions) {  // constant over the run; in every state so each file stands alone
    MeshField region{cp::grip_region.name, 1, std::vector<double>(N)};
    for (std::size_t i = 0; i < N; ++i) region.values[i] = regions->region_of_node()[static_cast<std::size_t>(m.node_of_input[i])];
    point_fields.push_back(std::move(region));
  }
  MeshField stress{cc::cauchy_stress.name, 6, std::vector<double>(6 * E), {"xx", "yy", "zz", "xy", "yz", "xz"}},
      vm{cc::von_mises.name, 1, std::vector<double>(E)}, material{cc::material.name, 1, std::vector<double>(E)},
      jac{cc::jacobian.name, 1, std::vector<double>(E)}, body{cc::body.name, 1, std::vector<double>(E)};
  for (std::size_t b = 0; b < m.bodies.size(); ++b)
    std::fill(body.values.begin() + static_cast<std::ptrdiff_t>(m.bodies[b].tet_begin),
              body.values.begin() + static_cast<std::ptrdiff_t>(m.bodies[b].tet_end), static_cast<double>(b));
  // The result fields the laws of this model add (hgo: fibre_stretch), 0 on the other laws' tets.
  std::vector<MeshField> law_fields;
  for (const auto& b : m.blocks)
    for (const auto& f : b.material.type().result_fields)
      if (std::none_of(law_fields.begin(), law_fields.end(), [&](const MeshField& x) { return x.name == f.name; }))
        law_fields.push_back({f.name, f.components, std::vector<double>(static_cast<std::size_t>(f.components) * E)});
  // Per block the law's result fields it fills, in its law's order (that of its records' values).
  std::vector<std::vector<MeshField*>> targets(m.blocks.size());
  for (std::size_t bi = 0; bi < m.blocks.size(); ++bi)
    for (const auto& f : m.blocks[bi].material.type().result_fields)
      for (auto& x : law_fields)
        if (x.name == f.name) targets[bi].push_back(&x);
  // The cells come with the records (the process that computed them holds their nodes; no process
  // need hold the whole connectivity), in the input numbering.
  std::vector<int> input_of(N);
  for (std::size_t i = 0; i < N; ++i) input_of[static_cast<std::size_t>(m.node_of_input[i])] = static_cast<int>(i);
  std::vector<std::array<int, 4>> cells(E);
  // Each tet's record straight into the fields (no array of every tet's at the writer's peak).
  cell_records([&](std::size_t bi, std::size_t e, const std::int32_t* nodes, const double* record) {
    const std::size_t out = static_cast<std::size_t>(m.input_element[e]);
    for (int k = 0; k < 4; ++k) cells[out][static_cast<std::size_t>(k)] = input_of[static_cast<std::size_t>(nodes[k])];
    for (int k = 0; k < 6; ++k) stress.values[6 * out + k] = record[k];
    vm.values[out] = record[6];
    block_peak[bi] = std::max(block_peak[bi], vm.values[out]);
    material.values[out] = static_cast<double>(bi);
    jac.values[out] = record[7];
    std::size_t at = kCellRecordFixed;
    for (MeshField* f : targets[bi]) {
      const auto n = static_cast<std::size_t>(f->components);
      for (std::size_t c = 0; c < n; ++c) f->values[n * out + c] = record[at++];
    }
  });
  std::vector<MeshField> cell_fields;
  for (MeshField* f : {&stress, &vm, &material, &body, &jac}) cell_fields.push_back(std::move(*f));
  for (auto& f : law_fields) cell_fields.push_back(std::move(f));
  // The names behind the "body" and "material" indices, so a plain VTK reader needs no run.json.
  MeshStrings body_names{contracts::kBodyNames, {}}, material_names{contracts::kMaterialNames, {}};
  for (const auto& b : m.bodies) body_names.values.push_back(b.name);
  for (const auto& b : m.blocks) material_names.values.push_back(b.name);
  std::vector<MeshStrings> names{body_names, material_names};
  if (regions) names.push_back({contracts::kGripRegionNames, regions->names()});
  write_vtu(file, m.input_mesh, std::move(cells), point_fields, cell_fields, current, time, names);
  return block_peak;
}

void write_pvd(const fs::path& file, const std::vector<std::pair<double, std::string>>& entries) {
  std::ostringstream o;
  o << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n";
  o << std::setprecision(12);
  for (const auto& [t, name] : entries) o << "    <DataSet timestep=\"" << t << "\" part=\"0\" file=\"" << name << "\"/>\n";
  o << "  </Collection>\n</VTKFile>\n";
  write_file(file, o.str());
}

void RunPeaks::add_contact_step(const ContactStepReport& cr, double t, const Vec3& peak_at, const std::vector<PairStepReport>& per_pair) {
  max_iterations = std::max(max_iterations, cr.iterations);
  recovering_rows += cr.recovering;
  rows_swept += cr.candidates, rows_in_order += cr.rows_in_order;
  if (pairs.size() != per_pair.size()) pairs.resize(per_pair.size());
  for (std::size_t k = 0; k < per_pair.size(); ++k) {
    const PairStepReport& p = per_pair[k];
    PairPeaks& q = pairs[k];
    if (const double f = norm(p.force); f > q.force) q.force = f, q.force_time = t, q.normal_force = p.normal_force;
    if (p.area > q.area) q.area = p.area, q.area_time = t;
    if (p.peak_pressure > q.pressure) q.pressure = p.peak_pressure, q.pressure_time = t;
  }
  if (cr.active == 0) return;
  ++contact_steps;
  const double f = norm(cr.force);
  if (f > force) force = f, force_time = t;
  if (cr.area > area) area = cr.area, area_time = t;
  if (cr.peak_step_pressure > step_pressure) step_pressure = cr.peak_step_pressure, step_pressure_time = t;
  if (cr.peak_pressure > pressure)
    pressure = cr.peak_pressure, pressure_time = t, pressure_at = peak_at, pressure_node = static_cast<std::size_t>(cr.peak_node);
}

}  // namespace tactus::solver
