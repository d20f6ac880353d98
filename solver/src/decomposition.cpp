#include "tactus/solver/decomposition.hpp"

#include <metis.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <sstream>

#include "tactus/core/error.hpp"
#include "tactus/core/file_io.hpp"

namespace tactus::solver {

namespace {

int tet_cost(const MaterialBlock& b) {
  if (!b.has_stress_pass()) return kRigidCost;
  return b.material.anp() ? kAnpCost : kStandardCost;
}

// Per node the tets that hold it, ascending (CSR: 4 bytes per tet corner). The decomposition's
// look-ups go through it rather than through a sorted list of every tet's four faces, which on a
// 1M-tet model took 96 MB (and its pairs 33 MB more) on every rank at the start of a run.
struct NodeTets {
  std::vector<std::size_t> first;  // num_nodes + 1
  std::vector<std::uint32_t> tets;
  explicit NodeTets(const Model& m) : first(m.num_nodes + 1, 0), tets(m.conn.size()) {
    for (const std::int32_t n : m.conn) ++first[static_cast<std::size_t>(n) + 1];
    for (std::size_t n = 0; n < m.num_nodes; ++n) first[n + 1] += first[n];
    std::vector<std::size_t> next(first.begin(), first.end() - 1);
    for (std::size_t corner = 0; corner < m.conn.size(); ++corner)
      tets[next[static_cast<std::size_t>(m.conn[corner])]++] = static_cast<std::uint32_t>(corner / 4);
  }
};

// f(a, b) once for each face two tets a < b share: the other tets at one of the face's nodes that
// hold its other two.
template <class F>
void for_each_shared_face(const Model& m, const NodeTets& at, F f) {
  const auto holds = [&](std::size_t t, std::int32_t n) {
    const std::int32_t* c = &m.conn[4 * t];
    return c[0] == n || c[1] == n || c[2] == n || c[3] == n;
  };
  for (std::size_t e = 0; e < m.conn.size() / 4; ++e)
    for (std::size_t skip = 0; skip < 4; ++skip) {
      std::int32_t face[3];
      for (std::size_t k = 0, i = 0; k < 4; ++k)
        if (k != skip) face[i++] = m.conn[4 * e + k];
      const auto n0 = static_cast<std::size_t>(face[0]);
      for (std::size_t k = at.first[n0]; k < at.first[n0 + 1]; ++k)
        if (const std::size_t t = at.tets[k]; t > e && holds(t, face[1]) && holds(t, face[2])) f(e, t);
    }
}

// The atoms' dual graph in METIS's compressed form, edges weighted by the faces two atoms share.
struct AtomGraph {
  std::vector<idx_t> xadj{0}, adjncy, adjwgt;
};
AtomGraph atom_graph(const Model& m, const NodeTets& at, const Decomposition& d) {
  std::vector<std::map<std::uint32_t, idx_t>> links(d.atom_cost.size());
  for_each_shared_face(m, at, [&](std::size_t a, std::size_t b) {
    const std::uint32_t x = d.tet_atom[a], y = d.tet_atom[b];
    if (x != y) ++links[x][y], ++links[y][x];
  });
  AtomGraph g;
  for (const auto& l : links) {
    for (const auto& [other, w] : l) g.adjncy.push_back(static_cast<idx_t>(other)), g.adjwgt.push_back(w);
    g.xadj.push_back(static_cast<idx_t>(g.adjncy.size()));
  }
  return g;
}

// Whether every atom reaches every other through the graph (METIS refuses a contiguous partition
// of a disconnected graph: several bodies).
bool connected(const AtomGraph& g) {
  const std::size_t n = g.xadj.size() - 1;
  std::vector<char> seen(n, 0);
  std::vector<std::size_t> stack{0};
  seen[0] = 1;
  std::size_t reached = 1;
  while (!stack.empty()) {
    const std::size_t a = stack.back();
    stack.pop_back();
    for (idx_t k = g.xadj[a]; k < g.xadj[a + 1]; ++k) {
      const auto b = static_cast<std::size_t>(g.adjncy[static_cast<std::size_t>(k)]);
      if (!seen[b]) seen[b] = 1, ++reached, stack.push_back(b);
    }
  }
  return reached == n;
}

// The quality of d's ranks; g: its atoms' graph (a face inside an atom never crosses ranks, so the
// faces cut are the weights of the graph's edges between ranks, each edge listed from both ends).
void measure(const Model& m, const NodeTets& at, const AtomGraph& g, Decomposition& d) {
  const std::size_t tets = m.conn.size() / 4;
  const auto rank_of = [&](std::size_t e) { return d.atom_rank[d.tet_atom[e]]; };
  std::size_t cut_twice = 0;
  for (std::size_t a = 0; a + 1 < g.xadj.size(); ++a)
    for (auto k = static_cast<std::size_t>(g.xadj[a]); k < static_cast<std::size_t>(g.xadj[a + 1]); ++k)
      if (d.atom_rank[a] != d.atom_rank[static_cast<std::size_t>(g.adjncy[k])]) cut_twice += static_cast<std::size_t>(g.adjwgt[k]);
  d.edge_cut_faces = cut_twice / 2;
  const auto ranks = static_cast<std::size_t>(d.ranks);
  d.rank_cost.assign(ranks, 0);
  d.rank_tets.assign(ranks, 0);
  d.halo_nodes.assign(ranks, 0);
  for (std::size_t atom = 0; atom < d.atom_rank.size(); ++atom) d.rank_cost[static_cast<std::size_t>(d.atom_rank[atom])] += d.atom_cost[atom];
  for (std::size_t e = 0; e < tets; ++e) ++d.rank_tets[static_cast<std::size_t>(rank_of(e))];
  // A node whose tets two ranks hold is in both ranks' halos.
  std::vector<std::int32_t> holders;
  for (std::size_t n = 0; n < m.num_nodes; ++n) {
    holders.clear();
    for (std::size_t k = at.first[n]; k < at.first[n + 1]; ++k)
      if (const std::int32_t r = rank_of(at.tets[k]); std::find(holders.begin(), holders.end(), r) == holders.end()) holders.push_back(r);
    if (holders.size() > 1)
      for (const std::int32_t r : holders) ++d.halo_nodes[static_cast<std::size_t>(r)];
  }
  std::int64_t total = 0, heaviest = 0;
  for (const std::int64_t c : d.rank_cost) total += c, heaviest = std::max(heaviest, c);
  d.load_imbalance = total > 0 ? static_cast<double>(heaviest) * static_cast<double>(ranks) / static_cast<double>(total) - 1 : 0;
}

// The atoms of the model (decomposition.hpp), with their costs; ranks not yet given.
Decomposition make_atoms(const Model& model, int ranks, std::size_t atom_tets) {
  if (atom_tets < 1) throw InputError("decomposition", "atom size", "at least one tet", "0");
  Decomposition d;
  d.ranks = ranks;
  d.atom_tets = atom_tets;
  d.tet_atom.assign(model.conn.size() / 4, 0);
  for (const MaterialBlock& b : model.blocks)
    for (std::size_t start = b.begin; start < b.end; start += atom_tets) {
      const std::size_t end = std::min(b.end, start + atom_tets);
      const auto atom = static_cast<std::uint32_t>(d.atom_cost.size());
      for (std::size_t e = start; e < end; ++e) d.tet_atom[e] = atom;
      d.atom_cost.push_back(static_cast<std::int64_t>(end - start) * tet_cost(b));
    }
  return d;
}

}  // namespace

Decomposition decompose(const Model& model, int ranks, std::size_t atom_tets, const std::string& what) {
  Decomposition d = make_atoms(model, ranks, atom_tets);
  const std::size_t atoms = d.atom_cost.size();
  if (ranks < 1 || static_cast<std::size_t>(ranks) > atoms)
    throw InputError("command line", what,
                     "1 to " + std::to_string(atoms) + " ranks (one atom of " + std::to_string(atom_tets) + " tets each at least)",
                     std::to_string(ranks));
  d.atom_rank.assign(atoms, 0);
  const NodeTets at(model);
  AtomGraph g = atom_graph(model, at, d);  // (METIS takes its arrays as non-const)
  if (ranks > 1) {
    std::vector<idx_t> weight(d.atom_cost.begin(), d.atom_cost.end()), part(atoms, 0);
    idx_t n = static_cast<idx_t>(atoms), constraints = 1, parts = ranks, cut = 0;
    idx_t options[METIS_NOPTIONS];
    METIS_SetDefaultOptions(options);
    options[METIS_OPTION_SEED] = 1;                       // the same parts on every run and every rank
    options[METIS_OPTION_UFACTOR] = 30;                   // at most 3 % above the mean cost (METIS's tolerance, in per mille)
    options[METIS_OPTION_CONTIG] = connected(g) ? 1 : 0;  // each rank's atoms connected where the graph is (one body)
    options[METIS_OPTION_NUMBERING] = 0;
    const int status = METIS_PartGraphKway(&n, &constraints, g.xadj.data(), g.adjncy.data(), weight.data(), nullptr, g.adjwgt.data(), &parts, nullptr,
                                           nullptr, options, &cut, part.data());
    if (status != METIS_OK) throw NumericalError("decomposition: METIS failed (status " + std::to_string(status) + ")");
    for (std::size_t a = 0; a < atoms; ++a) d.atom_rank[a] = static_cast<std::int32_t>(part[a]);
  }
  measure(model, at, g, d);
  return d;
}

Decomposition read_partition(const Model& model, const std::filesystem::path& file) {
  const std::string name = file.string();
  require_regular_file(file, "a partition (JSON)");
  std::ifstream in(file);
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_discarded() || !j.is_object()) throw InputError(name, "", "a JSON object {\"ranks\", \"atom_tets\", \"atom_rank\"}", "other text");
  const auto whole = [&](const char* key, long lo, long hi) {
    if (!j.contains(key) || !j[key].is_number_integer() || j[key].get<long>() < lo || j[key].get<long>() > hi)
      throw InputError(name, key, "a whole number from " + std::to_string(lo) + " to " + std::to_string(hi),
                       j.contains(key) ? j[key].dump() : "missing");
    return j[key].get<long>();
  };
  const long atom_tets = whole("atom_tets", 1, 1000000);
  Decomposition d = make_atoms(model, 1, static_cast<std::size_t>(atom_tets));
  const std::size_t atoms = d.atom_cost.size();
  d.ranks = static_cast<int>(whole("ranks", 1, static_cast<long>(atoms)));
  const auto& ranks = j.contains("atom_rank") ? j["atom_rank"] : nlohmann::json();
  if (!ranks.is_array() || ranks.size() != atoms)
    throw InputError(name, "atom_rank", "a list of " + std::to_string(atoms) + " ranks (the model's atoms of " + std::to_string(atom_tets) + " tets)",
                     ranks.is_array() ? std::to_string(ranks.size()) + " entries" : "no list");
  std::vector<std::size_t> count(static_cast<std::size_t>(d.ranks), 0);
  for (std::size_t a = 0; a < atoms; ++a) {
    if (!ranks[a].is_number_integer() || ranks[a].get<long>() < 0 || ranks[a].get<long>() >= d.ranks)
      throw InputError(name, "atom_rank[" + std::to_string(a) + "]", "a rank from 0 to " + std::to_string(d.ranks - 1), ranks[a].dump());
    d.atom_rank.push_back(ranks[a].get<std::int32_t>());
    ++count[static_cast<std::size_t>(d.atom_rank.back())];
  }
  for (std::size_t r = 0; r < count.size(); ++r)
    if (count[r] == 0)
      throw InputError(name, "atom_rank", "every rank from 0 to " + std::to_string(d.ranks - 1) + " given an atom",
                       "none for rank " + std::to_string(r));
  const NodeTets at(model);
  measure(model, at, atom_graph(model, at, d), d);
  return d;
}

nlohmann::json decomposition_json(const Decomposition& d) {
  return {{"format", "tactus decomposition"},
          {"ranks", d.ranks},
          {"atom_tets", d.atom_tets},
          {"edge_cut_faces", d.edge_cut_faces},
          {"load_imbalance", d.load_imbalance},
          {"rank_tets", d.rank_tets},
          {"rank_cost", d.rank_cost},
          {"halo_nodes", d.halo_nodes},
          {"atom_rank", d.atom_rank}};
}

std::string format_decomposition(const Decomposition& d) {
  std::ostringstream o;
  o << d.ranks << " rank(s), " << d.atom_rank.size() << " atoms of up to " << d.atom_tets << " tets; edge cut " << d.edge_cut_faces
    << " faces; load imbalance " << 100 * d.load_imbalance << " %\n";
  o << "rank      tets      cost  halo nodes\n";
  for (std::size_t r = 0; r < d.rank_cost.size(); ++r) o << r << "  " << d.rank_tets[r] << "  " << d.rank_cost[r] << "  " << d.halo_nodes[r] << "\n";
  return o.str();
}

}  // namespace tactus::solver
