// VTK XML unstructured grid (.vtu) output and input of tet meshes with fields.
#include <vtkCellData.h>
#include <vtkCellType.h>
#include <vtkDoubleArray.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include "tactus/core/error.hpp"
#include "tactus/core/mesh.hpp"
#include "tactus/core/staged_output.hpp"

namespace fs = std::filesystem;

namespace tactus {

namespace {

vtkSmartPointer<vtkDoubleArray> to_vtk(const MeshField& f, std::size_t expected_tuples, const std::string& file) {
  if (f.components < 1 || f.values.size() != expected_tuples * static_cast<std::size_t>(f.components))
    throw InputError(file, "field " + f.name,
                     std::to_string(expected_tuples) + " tuples of " + std::to_string(f.components),
                     std::to_string(f.values.size()) + " values");
  auto a = vtkSmartPointer<vtkDoubleArray>::New();
  a->SetName(f.name.c_str());
  a->SetNumberOfComponents(f.components);
  a->SetNumberOfTuples(static_cast<vtkIdType>(expected_tuples));
  std::copy(f.values.begin(), f.values.end(), a->GetPointer(0));
  return a;
}

MeshField from_vtk(vtkDataArray* a) {
  MeshField f;
  f.name = a->GetName() ? a->GetName() : "";
  f.components = a->GetNumberOfComponents();
  f.values.resize(static_cast<std::size_t>(a->GetNumberOfTuples() * f.components));
  for (vtkIdType i = 0; i < a->GetNumberOfTuples(); ++i)
    for (int c = 0; c < f.components; ++c)
      f.values[static_cast<std::size_t>(i * f.components + c)] = a->GetComponent(i, c);
  return f;
}

}  // namespace

void write_vtu(const fs::path& file, const TetMesh& mesh, const std::vector<MeshField>& point_fields,
               const std::vector<MeshField>& cell_fields, const std::vector<Vec3>* current_nodes) {
  const std::string fname = file.string();
  const auto& xyz = current_nodes ? *current_nodes : mesh.nodes;
  if (xyz.size() != mesh.nodes.size())
    throw InputError(fname, "current nodes", std::to_string(mesh.nodes.size()) + " positions");
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(static_cast<vtkIdType>(xyz.size()));
  for (std::size_t i = 0; i < xyz.size(); ++i) points->SetPoint(static_cast<vtkIdType>(i), xyz[i].data());
  vtkNew<vtkUnstructuredGrid> grid;
  grid->SetPoints(points);
  grid->Allocate(static_cast<vtkIdType>(mesh.tets.size()));
  for (const auto& t : mesh.tets) {
    const vtkIdType ids[4] = {t[0], t[1], t[2], t[3]};
    grid->InsertNextCell(VTK_TETRA, 4, ids);
  }
  vtkNew<vtkIntArray> group;
  group->SetName("group");
  group->SetNumberOfTuples(static_cast<vtkIdType>(mesh.tets.size()));
  for (std::size_t e = 0; e < mesh.tets.size(); ++e) group->SetValue(static_cast<vtkIdType>(e), mesh.tet_group[e]);
  grid->GetCellData()->AddArray(group);
  for (const auto& f : point_fields) grid->GetPointData()->AddArray(to_vtk(f, mesh.nodes.size(), fname));
  for (const auto& f : cell_fields) grid->GetCellData()->AddArray(to_vtk(f, mesh.tets.size(), fname));

  StagedOutput out(file);
  vtkNew<vtkXMLUnstructuredGridWriter> writer;
  writer->SetFileName(out.path().c_str());
  writer->SetInputData(grid);
  writer->SetDataModeToAppended();
  writer->SetCompressorTypeToZLib();
  if (writer->Write() != 1) throw InputError(fname, "", "a writable .vtu file");
  out.commit();
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

VtuContents read_vtu(const fs::path& file) {
  const std::string fname = file.string();
  if (!fs::exists(file)) throw InputError(fname, "", "an existing .vtu file", "no such file");
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  reader->SetFileName(fname.c_str());
  reader->Update();
  vtkUnstructuredGrid* grid = reader->GetOutput();
  if (reader->GetErrorCode() != 0 || !grid || grid->GetNumberOfPoints() == 0)
    throw InputError(fname, "", "a VTK XML unstructured grid (.vtu)", "unreadable or empty");
  VtuContents out;
  out.mesh.nodes.resize(static_cast<std::size_t>(grid->GetNumberOfPoints()));
  for (vtkIdType i = 0; i < grid->GetNumberOfPoints(); ++i) grid->GetPoint(i, out.mesh.nodes[static_cast<std::size_t>(i)].data());
  vtkDataArray* group = grid->GetCellData()->GetArray("group");
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c) {
    if (grid->GetCellType(c) != VTK_TETRA)
      throw InputError(fname, "cell " + std::to_string(c), "4-node tetrahedra only");
    vtkIdType npts;
    const vtkIdType* ids;
    grid->GetCellPoints(c, npts, ids);
    out.mesh.tets.push_back({static_cast<int>(ids[0]), static_cast<int>(ids[1]), static_cast<int>(ids[2]),
                             static_cast<int>(ids[3])});
    out.mesh.tet_group.push_back(group ? static_cast<int>(group->GetComponent(c, 0)) : 1);
  }
  for (int tag : out.mesh.tet_group)
    if (!out.mesh.find_group(3, tag)) out.mesh.groups.push_back({3, tag, "group_" + std::to_string(tag)});
  for (int i = 0; i < grid->GetPointData()->GetNumberOfArrays(); ++i)
    out.point_fields.push_back(from_vtk(grid->GetPointData()->GetArray(i)));
  for (int i = 0; i < grid->GetCellData()->GetNumberOfArrays(); ++i) {
    vtkDataArray* a = grid->GetCellData()->GetArray(i);
    if (a != group) out.cell_fields.push_back(from_vtk(a));
  }
  return out;
}

}  // namespace tactus
