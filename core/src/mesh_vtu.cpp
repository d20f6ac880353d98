// VTK XML unstructured grid (.vtu) output and input of tet meshes with fields.
#include <vtkCellData.h>
#include <vtkCellType.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkIdTypeArray.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkObject.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkStringArray.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>
#include <vtkXMLUnstructuredGridWriter.h>
#include <functional>

#include <cmath>

#include "tactus/core/contracts.hpp"
#include "tactus/core/error.hpp"
#include "tactus/core/file_io.hpp"
#include "tactus/core/isolated.hpp"
#include "tactus/core/mesh.hpp"
#include "tactus/core/staged_output.hpp"

namespace fs = std::filesystem;

namespace tactus {

namespace {

vtkSmartPointer<vtkDoubleArray> to_vtk(const MeshField& f, std::size_t expected_tuples, const std::string& file) {
  if (f.components < 1 || f.values.size() != expected_tuples * static_cast<std::size_t>(f.components))
    throw InputError(file, "field " + f.name, std::to_string(expected_tuples) + " tuples of " + std::to_string(f.components),
                     std::to_string(f.values.size()) + " values");
  auto a = vtkSmartPointer<vtkDoubleArray>::New();
  a->SetName(f.name.c_str());
  a->SetNumberOfComponents(f.components);
  // The array reads the field's own values (save = 1: VTK never frees or writes them), not a copy:
  // the field outlives the writer, and a state of a 1M-tet model saves about 100 MB of copies.
  a->SetArray(const_cast<double*>(f.values.data()), static_cast<vtkIdType>(f.values.size()), 1);
  if (f.component_names.size() == static_cast<std::size_t>(f.components))
    for (int c = 0; c < f.components; ++c) a->SetComponentName(c, f.component_names[static_cast<std::size_t>(c)].c_str());
  return a;
}

MeshField from_vtk(vtkDataArray* a) {
  MeshField f;
  f.name = a->GetName() ? a->GetName() : "";
  f.components = a->GetNumberOfComponents();
  f.values.resize(static_cast<std::size_t>(a->GetNumberOfTuples() * f.components));
  for (vtkIdType i = 0; i < a->GetNumberOfTuples(); ++i)
    for (int c = 0; c < f.components; ++c) f.values[static_cast<std::size_t>(i * f.components + c)] = a->GetComponent(i, c);
  return f;
}

// The grid's writer: `nodes` points, tet e's nodes from tet_nodes(e); cells_inserted runs once VTK
// holds its own copy of the cells.
using TetNodes = std::function<std::array<int, 4>(std::size_t tet)>;
void write_grid(const fs::path& file, const TetMesh& mesh, std::size_t nodes, std::size_t tets, const TetNodes& tet_nodes,
                const std::function<void()>& cells_inserted, const std::vector<MeshField>& point_fields, const std::vector<MeshField>& cell_fields,
                const std::vector<Vec3>* current_nodes, std::optional<double> time, const std::vector<MeshStrings>& strings) {
  const std::string fname = file.string();
  if (mesh.tet_group.size() != tets)
    throw InputError(fname, "tet groups", std::to_string(tets) + " (one per tet)", std::to_string(mesh.tet_group.size()));
  const auto& xyz = current_nodes ? *current_nodes : mesh.nodes;
  if (xyz.size() != nodes) throw InputError(fname, "current nodes", std::to_string(nodes) + " positions");
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(static_cast<vtkIdType>(xyz.size()));
  for (std::size_t i = 0; i < xyz.size(); ++i) points->SetPoint(static_cast<vtkIdType>(i), xyz[i].data());
  vtkNew<vtkUnstructuredGrid> grid;
  grid->SetPoints(points);
  grid->AllocateExact(static_cast<vtkIdType>(tets), 4 * static_cast<vtkIdType>(tets));  // no growth by doubling: a copy of every cell at the peak
  for (std::size_t e = 0; e < tets; ++e) {
    const std::array<int, 4> t = tet_nodes(e);
    const vtkIdType ids[4] = {t[0], t[1], t[2], t[3]};
    grid->InsertNextCell(VTK_TETRA, 4, ids);
  }
  if (cells_inserted) cells_inserted();
  vtkNew<vtkIntArray> group;
  group->SetName("group");
  group->SetNumberOfTuples(static_cast<vtkIdType>(tets));
  for (std::size_t e = 0; e < tets; ++e) group->SetValue(static_cast<vtkIdType>(e), mesh.tet_group[e]);
  grid->GetCellData()->AddArray(group);
  // 1-based ids, as every message, summary and quality.json counts (ParaView's own ids start at 0).
  vtkNew<vtkIdTypeArray> node_id, tet_id;
  node_id->SetName(contracts::point::node_id.name);
  node_id->SetNumberOfTuples(static_cast<vtkIdType>(nodes));
  for (vtkIdType i = 0; i < node_id->GetNumberOfTuples(); ++i) node_id->SetValue(i, i + 1);
  tet_id->SetName(contracts::cell::tet_id.name);
  tet_id->SetNumberOfTuples(static_cast<vtkIdType>(tets));
  for (vtkIdType e = 0; e < tet_id->GetNumberOfTuples(); ++e) tet_id->SetValue(e, e + 1);
  grid->GetPointData()->AddArray(node_id);
  grid->GetCellData()->AddArray(tet_id);
  for (const auto& f : point_fields) grid->GetPointData()->AddArray(to_vtk(f, nodes, fname));
  for (const auto& f : cell_fields) grid->GetCellData()->AddArray(to_vtk(f, tets, fname));
  vtkNew<vtkStringArray> units;  // every tactus file says its units
  units->SetName("units");
  units->InsertNextValue("SI (m, kg, s, Pa, J)");
  grid->GetFieldData()->AddArray(units);
  vtkNew<vtkStringArray> points_note;
  points_note->SetName(contracts::kPointsNote);
  points_note->InsertNextValue(current_nodes ? "current (deformed) configuration; reference = points - displacement (do not warp by it again)"
                                             : "reference configuration");
  grid->GetFieldData()->AddArray(points_note);
  for (const MeshStrings& named : strings) {
    vtkNew<vtkStringArray> a;
    a->SetName(named.name.c_str());
    for (const std::string& v : named.values) a->InsertNextValue(v);
    grid->GetFieldData()->AddArray(a);
  }
  if (time) {  // ParaView's name for a dataset's time
    vtkNew<vtkDoubleArray> t;
    t->SetName("TimeValue");
    t->InsertNextValue(*time);
    grid->GetFieldData()->AddArray(t);
  }

  StagedOutput out(file);
  vtkNew<vtkXMLUnstructuredGridWriter> writer;
  writer->SetFileName(out.path().c_str());
  writer->SetInputData(grid);
  writer->SetDataModeToAppended();
  writer->SetCompressorTypeToZLib();
  if (writer->Write() != 1 || writer->GetErrorCode() != 0) throw_library_write_failure(file, "VTK failed writing the grid");
  out.commit("</VTKFile>\n", "VTK grid");
}

}  // namespace

void write_vtu(const fs::path& file, const TetMesh& mesh, const std::vector<MeshField>& point_fields, const std::vector<MeshField>& cell_fields,
               const std::vector<Vec3>* current_nodes, std::optional<double> time, const std::vector<MeshStrings>& strings) {
  write_grid(
      file, mesh, mesh.nodes.size(), mesh.tets.size(), [&](std::size_t e) { return mesh.tets[e]; }, {}, point_fields, cell_fields, current_nodes,
      time, strings);
}

void write_vtu(const fs::path& file, const TetMesh& mesh, std::vector<std::array<int, 4>>&& cells, const std::vector<MeshField>& point_fields,
               const std::vector<MeshField>& cell_fields, const std::vector<Vec3>& current_nodes, std::optional<double> time,
               const std::vector<MeshStrings>& strings) {
  std::vector<std::array<int, 4>> held = std::move(cells);
  write_grid(
      file, mesh, current_nodes.size(), held.size(), [&](std::size_t e) { return held[e]; }, [&] { held = std::vector<std::array<int, 4>>(); },
      point_fields, cell_fields, &current_nodes, time, strings);
}

const MeshField* VtuContents::point_field(std::string_view name) const {
  for (const auto& f : point_fields)
    if (f.name == name) return &f;
  return nullptr;
}
const MeshField* VtuContents::cell_field(std::string_view name) const {
  for (const auto& f : cell_fields)
    if (f.name == name) return &f;
  return nullptr;
}

namespace {

// The direct read with VTK, run in an isolated child process (see read_vtu).
VtuContents read_vtu_direct(const fs::path& file) {
  const std::string fname = file.string();
  vtkObject::GlobalWarningDisplayOff();  // (in the child: our message replaces VTK's)
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  reader->SetFileName(fname.c_str());
  reader->Update();
  vtkUnstructuredGrid* grid = reader->GetOutput();
  if (reader->GetErrorCode() != 0 || !grid || grid->GetNumberOfPoints() == 0)
    throw InputError(fname, "", "a VTK XML unstructured grid (.vtu)", "unreadable or empty");
  VtuContents out;
  const vtkIdType np = grid->GetNumberOfPoints();
  out.mesh.nodes.resize(static_cast<std::size_t>(np));
  for (vtkIdType i = 0; i < np; ++i) {
    auto& x = out.mesh.nodes[static_cast<std::size_t>(i)];
    grid->GetPoint(i, x.data());
    for (double c : x)
      if (!std::isfinite(c)) throw InputError(fname, "point " + std::to_string(i), "finite coordinates", "a NaN or infinity");
  }
  vtkDataArray* group = grid->GetCellData()->GetArray("group");
  if (group && (group->GetNumberOfComponents() != 1 || group->GetNumberOfTuples() != grid->GetNumberOfCells()))
    throw InputError(fname, "group", "one value per cell");
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c) {
    if (grid->GetCellType(c) != VTK_TETRA) throw InputError(fname, "cell " + std::to_string(c), "4-node tetrahedra only");
    vtkIdType npts;
    const vtkIdType* ids;
    grid->GetCellPoints(c, npts, ids);
    if (npts != 4) throw InputError(fname, "cell " + std::to_string(c), "4 points", std::to_string(npts));
    for (int k = 0; k < 4; ++k)
      if (ids[k] < 0 || ids[k] >= np)
        throw InputError(fname, "cell " + std::to_string(c), "point ids below " + std::to_string(np), std::to_string(ids[k]));
    out.mesh.tets.push_back({static_cast<int>(ids[0]), static_cast<int>(ids[1]), static_cast<int>(ids[2]), static_cast<int>(ids[3])});
    const double g = group ? group->GetComponent(c, 0) : 1.0;
    if (!(g >= 1 && g <= 2e9) || g != std::floor(g))
      throw InputError(fname, "group of cell " + std::to_string(c), "a positive integer tag", std::to_string(g));
    out.mesh.tet_group.push_back(static_cast<int>(g));
  }
  for (int tag : out.mesh.tet_group)
    if (!out.mesh.find_group(3, tag)) out.mesh.groups.push_back({3, tag, "group_" + std::to_string(tag)});
  auto fields = [&](vtkFieldData* data, std::size_t tuples, std::vector<MeshField>& into, vtkDataArray* skip) {
    for (int i = 0; i < data->GetNumberOfArrays(); ++i) {
      vtkDataArray* a = data->GetArray(i);
      if (!a || a == skip) continue;  // (string arrays are not data arrays)
      if (static_cast<std::size_t>(a->GetNumberOfTuples()) != tuples || a->GetNumberOfComponents() < 1)
        throw InputError(fname, a->GetName() ? a->GetName() : "unnamed array", std::to_string(tuples) + " tuples",
                         std::to_string(a->GetNumberOfTuples()));
      into.push_back(from_vtk(a));
    }
  };
  fields(grid->GetPointData(), out.mesh.nodes.size(), out.point_fields, nullptr);
  fields(grid->GetCellData(), out.mesh.tets.size(), out.cell_fields, group);
  if (vtkDataArray* t = grid->GetFieldData() ? grid->GetFieldData()->GetArray("TimeValue") : nullptr;
      t && t->GetNumberOfTuples() == 1 && t->GetNumberOfComponents() == 1 && std::isfinite(t->GetComponent(0, 0)))
    out.time = t->GetComponent(0, 0);
  return out;
}

void put_fields(ByteWriter& w, const std::vector<MeshField>& fields) {
  w.put<std::uint64_t>(fields.size());
  for (const auto& f : fields) w.put_string(f.name), w.put(f.components), w.put_vector(f.values);
}

}  // namespace

VtuContents read_vtu(const fs::path& file) {
  const std::string fname = file.string();
  std::error_code ec;
  require_regular_file(file, "a VTK unstructured grid (.vtu)");
  // VTK's XML reader is not hardened against hostile bytes: it reads in an isolated child process.
  const std::string bytes = run_isolated(
      fname, "VTK unstructured grid (.vtu)",
      [&](ByteWriter& w) {
        const VtuContents v = read_vtu_direct(file);
        w.put_vector(v.mesh.nodes);
        w.put_vector(v.mesh.tets);
        w.put_vector(v.mesh.tet_group);
        put_fields(w, v.point_fields);
        put_fields(w, v.cell_fields);
        w.put<std::uint8_t>(v.time ? 1 : 0);
        w.put<double>(v.time.value_or(0.0));
      },
      limits_for_file(fname));
  ByteReader r(bytes);
  VtuContents out;
  out.mesh.nodes = r.get_vector<Vec3>();
  out.mesh.tets = r.get_vector<std::array<int, 4>>();
  out.mesh.tet_group = r.get_vector<int>();
  for (int tag : out.mesh.tet_group)
    if (!out.mesh.find_group(3, tag)) out.mesh.groups.push_back({3, tag, "group_" + std::to_string(tag)});
  for (auto* fields : {&out.point_fields, &out.cell_fields}) {
    const auto n = r.get<std::uint64_t>();
    for (std::uint64_t i = 0; i < n; ++i) {
      MeshField f;
      f.name = r.get_string();
      f.components = r.get<int>();
      f.values = r.get_vector<double>();
      fields->push_back(std::move(f));
    }
  }
  const bool has_time = r.get<std::uint8_t>() != 0;
  const double time = r.get<double>();
  if (has_time) out.time = time;
  return out;
}

}  // namespace tactus
