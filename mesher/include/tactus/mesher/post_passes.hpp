#pragma once
// The mesher's post-passes on a tet mesh, after CGAL (CGAL-free: they work on TetMesh alone and
// are tested on hand-made meshes): restoring each subdomain's volume, relocating the nodes of the
// tets that set the explicit time step, peeling soft-tissue slivers that lie flat on the skin, and
// rebuilding the boundary triangles from the tets' labels, and resolving the boundaries'
// non-manifold edges and vertices left after meshing. Their thresholds are in PostPassParams.
#include <array>
#include <cstddef>
#include <vector>

#include "tactus/core/mesh.hpp"
#include "tactus/core/volume.hpp"

namespace tactus::mesher {

struct PostPassParams {
  int volume_restore_attempts = 4;    // halvings of an offset that would invert a tet
  double relocate_ratio_goal = 0.35;  // relocate nodes of tets with L_e below this fraction of their subdomain's median
  int relocate_passes = 6;
  int relocate_iterations = 24;    // pattern-search iterations per node
  double crease_angle_deg = 50;    // surface nodes whose face normals differ more are not moved
  double dihedral_floor_deg = 10;  // a move never takes an incident tet's dihedral angle below this
  double peel_ratio_goal = 0.3;    // skin slivers below this fraction of the soft-tissue median are peeled
  double peel_pair_factor = 1.5;   // a neighbour peeled with one is short too: below this x peel_ratio_goal
  int peel_sweeps = 8;
  // The guarantees on any label volume: every tet's smallest dihedral angle and its L_e over its
  // subdomain's median at least these; the last pass aims this factor above them.
  double guarantee_dihedral_deg = 10;
  double guarantee_length_ratio = 0.2;
  double guarantee_margin = 1.1;
  int split_rounds = 4;  // rounds of interior-edge splits at the tets relocation cannot fix
};

// The tets around every node.
std::vector<std::vector<std::size_t>> tets_around_nodes(const TetMesh& mesh);
// Half the cross product of a triangle's edges: its normal with length equal to its area.
std::array<double, 3> area_normal(const TetMesh& mesh, const std::array<int, 3>& f);

// Restores the volume of every closed surface (each bone's interface, the skin for the whole
// body) to its label volume by one normal offset. triangle_inner[t]: the label inside triangle t
// (0 for the outer skin).
void restore_volumes(TetMesh& mesh, const Volume<std::uint8_t>& labels, const std::vector<int>& triangle_inner, const PostPassParams& p = {});
// Moves the nodes of the tets whose L_e is below p.relocate_ratio_goal of their subdomain's median.
void relocate_short_tets(TetMesh& mesh, double max_surface_move, const PostPassParams& p = {});
// Moves the nodes of the tets below the guarantees (dihedral angle or L_e ratio) to raise the
// worst of them; returns how many tets are still below.
std::size_t relocate_poor_tets(TetMesh& mesh, double max_surface_move, const PostPassParams& p = {});
// Merges a node into its neighbour across a short surface edge of a tet below the guarantees,
// where that raises the worst measure around them (edge_collapse.cpp); returns the number merged.
std::size_t collapse_poor_surface_edges(TetMesh& mesh, double max_surface_move, const PostPassParams& p = {});
// 2-3 face flips inside one subdomain where they raise the worst guarantee measure of the tets
// below the guarantees (flips.cpp: slivers flat on a surface, which relocation cannot lift);
// returns how many. Surfaces, interfaces and nodes are unchanged.
std::size_t flip_poor_tets(TetMesh& mesh, const PostPassParams& p = {});
// Gives each soft-tissue tet below the guarantees that has two faces on one bone to that bone, if
// it meets them there (wedges.cpp); returns how many. The boundary triangles are rebuilt.
std::size_t give_wedges_to_bone(TetMesh& mesh, const PostPassParams& p = {});
// One sweep of peeling; returns the number of tets removed (the boundary triangles are rebuilt).
std::size_t peel_skin_slivers(TetMesh& mesh, const PostPassParams& p = {});
// The faces between different labels (0 = outside): skin or bone interface, oriented outward.
void rebuild_boundary_triangles(TetMesh& mesh);

// What resolve_boundary_pinches did: the non-manifold edges and vertices of the skin and of every
// group's own boundary (as boundary_topology counts them) before and after, and the tets it
// relabelled or removed with their volume.
struct BoundaryPinchReport {
  std::size_t defects_before = 0, defects_after = 0;
  std::size_t tets_relabelled = 0, tets_removed = 0;
  double volume_moved_m3 = 0;
};
// Resolves the non-manifold edges and vertices left on the boundaries by relabelling or removing
// the tets of the smallest run around each (boundary_pinches.cpp); no node moves. The boundary
// triangles are rebuilt when anything changed.
BoundaryPinchReport resolve_boundary_pinches(TetMesh& mesh, const PostPassParams& p = {});

}  // namespace tactus::mesher
