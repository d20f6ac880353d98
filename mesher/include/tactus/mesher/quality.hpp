#pragma once
// Mesh quality for explicit dynamics: per-subdomain counts, dihedral angles, radius ratio, edge
// ratio, volumes, slivers, and the characteristic length L_e of core's stable-step function,
// from which the critical time step for given wave speeds follows.
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "tactus/core/mesh.hpp"

namespace tactus::mesher {

struct TetQuality {
  double min_dihedral_deg, max_dihedral_deg, radius_ratio, edge_ratio, volume, length;  // length = L_e
};
TetQuality tet_quality(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

// What the mesher guarantees in every subdomain (docs/design.md, "Mesh quality"): the smallest
// dihedral angle of any tet, and the smallest L_e over the subdomain's median L_e (the tet that
// sets the explicit time step is not much smaller than a typical one).
struct QualityGuarantees {
  double min_dihedral_deg = 10;
  double min_length_ratio = 0.2;
  // The step a subdomain pays: its critical step is at least min_length_ratio of its median tet's
  // own step (one wave speed per subdomain: the L_e ratio), or mass scaling lifts its few short tets
  // to that step by adding at most this fraction of the subdomain's mass.
  double max_added_mass_fraction = 0.01;
};

// What an unmet guarantee's "why" advises, per mesher: the defaults speak of the image mesher's
// surfaces and options; a gmsh object (box, STL) has its own.
struct QualityAdvice {
  std::string surface_angle =  // the worst tet's four nodes all on surfaces
      "its four nodes lie on the skin or a bone interface, where nodes move only within the surface approximation and only interior "
      "edges are split: a surface detail finer than the facet size (a smaller --facet-size / --bone-facet-size resolves it, a larger "
      "--facet-distance smooths it)";
  std::string interior_angle =
      "node relocation and interior edge splits could not raise it without making a neighbour worse (a region already below the "
      "length guarantee, or nodes pinned on surface creases)";
  std::string short_length =  // after "L_e .. mm against the subdomain's median .. mm: "
      "the label is thinner than its elements here (a narrow region or gap between two surfaces); absorb it (--min-region-mm3), smooth "
      "the labels, or accept the stable step it sets";
  static QualityAdvice gmsh_object();
};

// Report as JSON (written as quality.json). wave_speed(group tag) gives the dilatational speed
// used for the critical step (<= 0: group skipped). "guarantees" says whether `goal` is met in
// every subdomain and, for each unmet one, the worst tet, where it is and why.
nlohmann::json quality_report(const TetMesh& mesh, const std::map<int, double>& wave_speed, double sliver_deg = 10.0,
                              const QualityGuarantees& goal = {}, const QualityAdvice& advice = {});

}  // namespace tactus::mesher
