#pragma once
// Structured tet meshes of a box (sample meshes for the solver, its tests and benchmarks): each of nx*ny*nz hexahedral cells
// is split into 6 tets around its main diagonal (Kuhn split, conforming across cells).
// Physical groups: volume 1 "body"; surfaces 11..16 "xmin","xmax","ymin","ymax","zmin","zmax".
#include <cstdint>
#include <string>

#include "tactus/core/mesh.hpp"

namespace tactus::samples {

TetMesh make_box_mesh(int nx, int ny, int nz, double lx, double ly, double lz, Vec3 origin = {0, 0, 0});

// Moves interior nodes randomly by up to `fraction` of the cell size (irregular but valid mesh).
void perturb_interior_nodes(TetMesh& mesh, double cell_size, double fraction, std::uint64_t seed);

// Appends `other` to `mesh` as a separate body in the same file (tests and benchmarks of contact):
// its group tags are shifted by tag_offset and its group names get name_suffix.
void append_mesh(TetMesh& mesh, const TetMesh& other, int tag_offset, const std::string& name_suffix);

// Randomly renumbers nodes and elements, as a mesher without locality ordering would leave them.
void shuffle_numbering(TetMesh& mesh, std::uint64_t seed);

}  // namespace tactus::samples
