#pragma once
// The skeleton of a meshed hand (tactus-mesh skeleton): each bone group's principal axes, the
// bones' names and parents from the chains they form, and each joint's centre and axes
// (core/skeleton.hpp has the conventions; docs/design.md, "The skeleton", the rules).
//
// Naming. Two bones are neighbours when their surfaces come within `neighbour_gap_m`. A bone is
// long when it spreads at least twice as far along its principal axis as across it (phalanges,
// metacarpals), compact otherwise (carpals, the pisiform). A chain starts at a long bone with one
// neighbour (a distal phalanx) and steps to its one new long neighbour until a bone touches a
// compact one, the carpal it sits on. A chain of four bones is a finger (distal, middle, proximal
// phalanx, metacarpal), of three the thumb; the compact bones are roots. The fingers are ordered index to little by their metacarpals' distance from
// the thumb. Bone groups already named so (the phantom's labels), or a user's names file, take precedence.
#include <filesystem>
#include <map>
#include <string>

#include "tactus/core/mesh.hpp"
#include "tactus/core/skeleton.hpp"

namespace tactus::mesher {

struct SkeletonOptions {
  double neighbour_gap_m = 3.5e-3;   // the phantom's joints are 2.2 mm apart, its carpals 1.6 mm
  std::map<int, std::string> names;  // label -> bone name, from a names file; empty: the groups' own or inferred
  std::string source = "mesh";       // the mesh's file, for messages
};

// InputError naming the labels when the bones cannot be named (chains of the wrong length, not
// four fingers and a thumb), or when a name is unknown.
Skeleton extract_skeleton(const TetMesh& mesh, const SkeletonOptions& options);

// A names file: {"labels": {"<label>": "<bone name>", ...}} with the names skeleton.json uses
// (scaphoid ... hamate, metacarpal_<digit>, proximal_phalanx_<digit>, middle_phalanx_<finger>,
// distal_phalanx_<digit>; digits index, middle, ring, little, thumb).
std::map<int, std::string> read_bone_names(const std::filesystem::path& file);

}  // namespace tactus::mesher
