// gmsh MSH 4.1 writing through the gmsh API (libgmsh 4.8), and the gmsh model -> TetMesh
// conversion for meshes gmsh generates in memory. Reading .msh files is msh_reader.cpp's.
#include <gmsh.h>

#include <map>
#include <mutex>

#include "tactus/core/error.hpp"
#include "tactus/core/file_io.hpp"
#include "tactus/core/gmsh_session.hpp"
#include "tactus/core/mesh.hpp"
#include "tactus/core/staged_output.hpp"

namespace fs = std::filesystem;

namespace tactus {

namespace {

constexpr int kGmshTriangle = 2;  // gmsh element type codes
constexpr int kGmshTet = 4;

std::mutex& gmsh_mutex() {
  static std::mutex m;
  return m;
}

}  // namespace

GmshSession::GmshSession() : lock_(gmsh_mutex()) {
  gmsh::initialize(0, nullptr, false);
  gmsh::option::setNumber("General.Terminal", 0);
  gmsh::option::setNumber("General.Verbosity", 1);
}

GmshSession::~GmshSession() { gmsh::finalize(); }

std::string GmshSession::last_error() {
  std::string err;
  gmsh::logger::getLastError(err);
  return err.empty() ? "unreadable MSH data" : err;
}

void write_msh(const fs::path& file, const TetMesh& mesh, bool binary) {
  mesh.validate(file.string());
  StagedOutput out(file);
  {
    GmshSession session;
    gmsh::model::add("tactus");
    // One discrete entity per physical group; entity tag == physical tag within a dimension.
    std::vector<int> volume_tags, surface_tags;
    for (const auto& g : mesh.groups) (g.dim == 3 ? volume_tags : surface_tags).push_back(g.tag);
    if (volume_tags.empty()) throw InputError(file.string(), "physical volumes", "at least one group");
    for (int t : surface_tags) gmsh::model::addDiscreteEntity(2, t);
    for (int t : volume_tags) gmsh::model::addDiscreteEntity(3, t);

    // All nodes live on the first volume entity (gmsh requires every node on some entity).
    std::vector<std::size_t> node_tags(mesh.nodes.size());
    std::vector<double> coords(3 * mesh.nodes.size());
    for (std::size_t i = 0; i < mesh.nodes.size(); ++i) {
      node_tags[i] = i + 1;
      for (int c = 0; c < 3; ++c) coords[3 * i + c] = mesh.nodes[i][c];
    }
    gmsh::model::mesh::addNodes(3, volume_tags.front(), node_tags, coords);

    std::size_t next_element = 1;
    auto add_elements = [&](int dim, int tag, int type, auto const& cells, auto const& cell_group) {
      std::vector<std::size_t> etags, enodes;
      for (std::size_t e = 0; e < cells.size(); ++e) {
        if (cell_group[e] != tag) continue;
        etags.push_back(next_element++);
        for (int v : cells[e]) enodes.push_back(static_cast<std::size_t>(v) + 1);
      }
      gmsh::model::mesh::addElementsByType(tag, type, etags, enodes);
      (void)dim;
    };
    for (int t : volume_tags) add_elements(3, t, kGmshTet, mesh.tets, mesh.tet_group);
    for (int t : surface_tags) add_elements(2, t, kGmshTriangle, mesh.triangles, mesh.triangle_group);
    for (const auto& g : mesh.groups) {
      gmsh::model::addPhysicalGroup(g.dim, {g.tag}, g.tag);
      gmsh::model::setPhysicalName(g.dim, g.tag, g.name);
    }
    gmsh::option::setNumber("Mesh.MshFileVersion", 4.1);
    gmsh::option::setNumber("Mesh.Binary", binary ? 1 : 0);
    gmsh::option::setNumber("Mesh.SaveAll", 0);
    // gmsh picks the format from the extension: stage under a name ending in .msh.
    const fs::path staged_msh = out.path().string() + ".msh";
    try {
      gmsh::write(staged_msh.string());
    } catch (...) {
      throw_library_write_failure(file, "gmsh failed writing it: " + GmshSession::last_error());
    }
    std::error_code ec;
    fs::rename(staged_msh, out.path(), ec);
    if (ec) throw WriteError(file.string(), "gmsh wrote nothing there (" + ec.message() + ")");
  }
  // gmsh does not report a failed write: a file cut short by a full disk lacks its last section's end.
  out.commit("$EndElements\n", "MSH file");
}

TetMesh tet_mesh_from_gmsh_model(const std::string& fname) {
  TetMesh mesh;
  std::vector<std::size_t> node_tags;
  std::vector<double> coords, param;
  gmsh::model::mesh::getNodes(node_tags, coords, param, -1, -1, false, false);
  if (node_tags.empty()) throw InputError(fname, "$Nodes", "at least one node", "none");
  std::map<std::size_t, int> index_of;  // gmsh tags may be sparse
  mesh.nodes.resize(node_tags.size());
  for (std::size_t i = 0; i < node_tags.size(); ++i) {
    index_of[node_tags[i]] = static_cast<int>(i);
    mesh.nodes[i] = {coords[3 * i], coords[3 * i + 1], coords[3 * i + 2]};
  }
  auto node_index = [&](std::size_t tag) {
    auto it = index_of.find(tag);
    if (it == index_of.end()) throw InputError(fname, "$Elements", "node tags defined in $Nodes", "tag " + std::to_string(tag));
    return it->second;
  };

  gmsh::vectorpair groups;
  gmsh::model::getPhysicalGroups(groups);
  for (const auto& [dim, tag] : groups) {
    if (dim != 2 && dim != 3) continue;
    std::string name;
    gmsh::model::getPhysicalName(dim, tag, name);
    if (name.empty()) name = (dim == 3 ? "volume_" : "surface_") + std::to_string(tag);
    mesh.groups.push_back({dim, tag, name});
    std::vector<int> entities;
    gmsh::model::getEntitiesForPhysicalGroup(dim, tag, entities);
    for (int entity : entities) {
      std::vector<std::size_t> etags, enodes;
      if (dim == 3) {
        gmsh::model::mesh::getElementsByType(kGmshTet, etags, enodes, entity);
        for (std::size_t e = 0; e < etags.size(); ++e) {
          mesh.tets.push_back(
              {node_index(enodes[4 * e]), node_index(enodes[4 * e + 1]), node_index(enodes[4 * e + 2]), node_index(enodes[4 * e + 3])});
          mesh.tet_group.push_back(tag);
        }
      } else {
        gmsh::model::mesh::getElementsByType(kGmshTriangle, etags, enodes, entity);
        for (std::size_t e = 0; e < etags.size(); ++e) {
          mesh.triangles.push_back({node_index(enodes[3 * e]), node_index(enodes[3 * e + 1]), node_index(enodes[3 * e + 2])});
          mesh.triangle_group.push_back(tag);
        }
      }
    }
  }
  if (mesh.tets.empty())
    throw InputError(fname, "physical volumes", "4-node tetrahedra in at least one physical volume group",
                     "none (tactus assigns materials by physical group)");
  mesh.validate(fname);
  return mesh;
}

}  // namespace tactus
