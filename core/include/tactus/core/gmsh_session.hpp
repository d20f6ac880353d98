#pragma once
// gmsh keeps global state: one quiet session at a time, finalized on every path. Shared by the
// .msh reader/writer (core) and the object meshes of the mesher.
#include <mutex>
#include <string>

#include "tactus/core/mesh.hpp"

namespace tactus {

class GmshSession {
 public:
  GmshSession();
  ~GmshSession();
  GmshSession(const GmshSession&) = delete;
  GmshSession& operator=(const GmshSession&) = delete;
  // gmsh's last error message (for exceptions thrown by its API), or a generic one.
  static std::string last_error();

 private:
  std::unique_lock<std::mutex> lock_;
};

// The current gmsh model's tets and triangles, by physical group, as a TetMesh. `source` names
// the origin in error messages. Requires an open GmshSession.
TetMesh tet_mesh_from_gmsh_model(const std::string& source);

}  // namespace tactus
