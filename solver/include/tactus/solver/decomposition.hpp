#pragma once
// Domain decomposition for running one model on several ranks (issue: tactus-solve across
// machines). The unit is the atom: a run of consecutive tets of one material block (the model's
// element order, which is locality-ordered), of `atom_tets` tets except a block's last. Atoms do
// not depend on the number of ranks, so sums taken per atom in atom order can stay bit-identical at
// any rank count. The atoms' dual graph (two atoms adjacent when their tets share a face, weighted
// by the faces they share) is cut by METIS into `ranks` parts, each atom weighted by its stress
// pass's cost (kRigidCost, kStandardCost, kAnpCost per tet: the stress-pass bench's ns per tet,
// rounded). METIS runs with a fixed seed, so the same model and rank count give the same parts.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tactus/solver/model.hpp"

namespace tactus::solver {

// Relative stress-pass cost per tet (docs/studies/stress-pass-kernels.md: standard tets ~45 ns,
// ANP tets ~60-90 ns; a rigid piece's tets or a joint gap's carry no stress pass, only their nodes'
// share of the time integration).
inline constexpr int kRigidCost = 1, kStandardCost = 4, kAnpCost = 6;

struct Decomposition {
  int ranks = 1;
  std::size_t atom_tets = 0;
  std::vector<std::uint32_t> tet_atom;  // atom of each tet (model order)
  std::vector<std::int32_t> atom_rank;  // rank of each atom
  std::vector<std::int64_t> atom_cost;  // summed tet costs
  // The quality: faces between tets of different ranks, the heaviest rank's cost over the mean
  // minus 1, and per rank its cost and its halo nodes (nodes of its tets that tets of another rank
  // also hold).
  std::size_t edge_cut_faces = 0;
  double load_imbalance = 0;
  std::vector<std::int64_t> rank_cost;
  std::vector<std::size_t> rank_tets, halo_nodes;
};

// Atoms of the model and their ranks. `ranks` from 1 to the number of atoms; an InputError
// otherwise (naming `what`, e.g. "--ranks").
Decomposition decompose(const Model& model, int ranks, std::size_t atom_tets = kAtomTets, const std::string& what = "ranks");

// A partition given by the user instead of METIS (a cut placed on purpose: `tactus-solve decompose
// --partition FILE`): the JSON decomposition_json writes, of which "atom_tets", "ranks" and
// "atom_rank" (one rank per atom of this model) are read; its quality is measured as decompose's.
// An InputError names the file and the entry that is wrong (a list of another length, a rank out of
// range, a rank given no atom).
Decomposition read_partition(const Model& model, const std::filesystem::path& file);

// The decomposition as JSON ("format" "tactus decomposition"): ranks, atom_tets, the quality
// figures and atom_rank.
nlohmann::json decomposition_json(const Decomposition& d);

// The quality figures of a decomposition as a small table (what tactus-solve decompose prints).
std::string format_decomposition(const Decomposition& d);

}  // namespace tactus::solver
