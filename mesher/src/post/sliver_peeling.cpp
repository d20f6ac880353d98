// Peeling soft-tissue tets that lie flat on the skin (post_passes.hpp). Such a tet (two or three
// faces on the skin, or one with a short neighbour) whose characteristic length is below
// p.peel_ratio_goal of the soft-tissue median, or whose smallest dihedral angle is below the
// guarantee (p.guarantee_dihedral_deg), is a sliver of the surface approximation (its four
// nodes on the skin, e.g. at the wrist cut's rim or over a thin finger): no node can be moved to
// fix it without leaving the surface, and it sets the explicit time step. Removing it exposes its
// inner faces; the skin stays closed and 2-manifold (checked around every edge and node of the
// tet), every node stays in the mesh, and the volume lost is the sliver's (a fraction of a per mille).
#include <algorithm>
#include <map>
#include <set>

#include "tactus/core/contracts.hpp"
#include "tactus/core/log.hpp"
#include "tactus/mesher/post_passes.hpp"
#include "topology.hpp"

namespace tactus::mesher {

namespace {

constexpr int kSoft = contracts::kSoftTissueLabel;
using Face = std::array<int, 3>;

class SkinPeeler {
 public:
  SkinPeeler(TetMesh& mesh, const PostPassParams& p) : mesh_(mesh), p_(p), alive_(mesh.tets.size(), 1), tets_of_(tets_around_nodes(mesh)) {
    for (std::size_t e = 0; e < mesh.tets.size(); ++e)
      for (const auto& f : kFaces) owners_[face(e, f)].push_back(e);
  }

  std::size_t run() {
    std::vector<double> soft;
    for (std::size_t e = 0; e < mesh_.tets.size(); ++e)
      if (mesh_.tet_group[e] == kSoft) soft.push_back(length(e));
    if (soft.empty()) return 0;
    std::nth_element(soft.begin(), soft.begin() + static_cast<std::ptrdiff_t>(soft.size() / 2), soft.end());
    median_ = soft[soft.size() / 2];
    std::vector<std::pair<double, std::size_t>> candidates;
    for (std::size_t e = 0; e < mesh_.tets.size(); ++e)
      if (mesh_.tet_group[e] == kSoft && (length(e) < p_.peel_ratio_goal * median_ || min_dihedral(e) < p_.guarantee_dihedral_deg))
        candidates.push_back({length(e), e});
    std::sort(candidates.begin(), candidates.end());
    std::size_t removed = 0;
    for (const auto& [len, e] : candidates) removed += try_peel(e, len);
    if (removed > 0) keep_alive_tets(mesh_, alive_);
    return removed;
  }

 private:
  Face face(std::size_t e, const int* f) const { return sorted_face(mesh_.tets[e][f[0]], mesh_.tets[e][f[1]], mesh_.tets[e][f[2]]); }

  double length(std::size_t e) const { return std::max(0.0, tet_length(mesh_, mesh_.tets[e])); }  // 0: inverted or flat
  double min_dihedral(std::size_t e) const { return tet_min_dihedral(mesh_, mesh_.tets[e]); }

  std::size_t live_owners(const Face& key) {
    std::size_t n = 0;
    for (std::size_t e : owners_[key]) n += alive_[e];
    return n;
  }

  // Skin faces (one live soft-tissue owner, nothing behind) around a node, among its live tets.
  std::set<Face> skin_faces_at(int node) {
    std::set<Face> out;
    for (std::size_t e : tets_of_[static_cast<std::size_t>(node)]) {
      if (!alive_[e]) continue;
      for (const auto& f : kFaces) {
        const Face key = face(e, f);
        if ((key[0] == node || key[1] == node || key[2] == node) && live_owners(key) == 1 && mesh_.tet_group[e] != 0) out.insert(key);
      }
    }
    return out;
  }

  // One closed fan of faces around the node, each edge of it shared by exactly two faces.
  bool manifold_at(int node) {
    const auto faces = skin_faces_at(node);
    if (faces.empty()) return true;
    std::map<int, std::vector<Face>> by_edge;  // other end of the edge at `node`
    for (const auto& f : faces)
      for (int v : f)
        if (v != node) by_edge[v].push_back(f);
    for (const auto& [v, fs] : by_edge)
      if (fs.size() != 2) return false;
    std::set<Face> seen{*faces.begin()};
    std::vector<Face> stack{*faces.begin()};
    while (!stack.empty()) {
      const auto f = stack.back();
      stack.pop_back();
      for (int v : f)
        if (v != node)
          for (const auto& g : by_edge[v])
            if (seen.insert(g).second) stack.push_back(g);
    }
    return seen.size() == faces.size();
  }

  // Every node of tet e keeps a live tet (e itself not counted when `excluding`).
  bool nodes_keep_a_tet(std::size_t e, bool excluding) {
    for (int v : mesh_.tets[e]) {
      std::size_t n = 0;
      for (std::size_t o : tets_of_[static_cast<std::size_t>(v)]) n += alive_[o] && (!excluding || o != e);
      if (n == 0) return false;
    }
    return true;
  }

  // Removes e alone, or with a short soft neighbour, when the skin stays closed and manifold.
  std::size_t try_peel(std::size_t e, double len) {
    int on_skin = 0;
    bool ok = true;
    for (const auto& f : kFaces) {
      const Face key = face(e, f);
      if (live_owners(key) == 1) {
        ++on_skin;
      } else {
        for (std::size_t other : owners_[key])  // the face becomes skin: only over soft tissue
          if (other != e && alive_[other] && mesh_.tet_group[other] != kSoft) ok = false;
      }
    }
    log::debug() << "peel: tet " << e << " L/median " << len / median_ << ", " << on_skin << " faces on the skin, faces over soft tissue " << ok;
    if (!ok || on_skin < 1 || !nodes_keep_a_tet(e, true)) return 0;
    alive_[e] = 0;
    for (int v : mesh_.tets[e]) ok = ok && manifold_at(v);
    log::debug() << "peel: tet " << e << " nodes kept; manifold after removal " << ok;
    if (ok) return 1;
    // Alone it would pinch the skin (e.g. across the sharp rim of the wrist cut): try it together
    // with one soft-tissue neighbour that is short too.
    if (const std::size_t n = try_pair(e)) return n;
    alive_[e] = 1;
    return 0;
  }

  std::size_t try_pair(std::size_t e) {
    for (const auto& f : kFaces)
      for (std::size_t other : owners_[face(e, f)]) {
        if (other == e || !alive_[other] || mesh_.tet_group[other] != kSoft) continue;
        if (length(other) >= p_.peel_pair_factor * p_.peel_ratio_goal * median_ && min_dihedral(other) >= p_.guarantee_dihedral_deg) continue;
        bool behind_soft = true;  // the pair's faces that become skin lie over soft tissue
        for (const auto& g : kFaces)
          for (std::size_t o : owners_[face(other, g)])
            behind_soft = behind_soft && (o == e || o == other || !alive_[o] || mesh_.tet_group[o] == kSoft);
        if (!behind_soft) continue;
        alive_[other] = 0;
        bool good = true;
        for (std::size_t tet : {e, other})
          for (int v : mesh_.tets[tet]) {
            std::size_t n = 0;
            for (std::size_t o : tets_of_[static_cast<std::size_t>(v)]) n += alive_[o];
            good = good && n > 0 && manifold_at(v);
          }
        if (good) return 2;
        alive_[other] = 1;
      }
    return 0;
  }

  TetMesh& mesh_;
  const PostPassParams& p_;
  std::vector<char> alive_;
  std::vector<std::vector<std::size_t>> tets_of_;
  std::map<Face, std::vector<std::size_t>> owners_;
  double median_ = 0;
};

}  // namespace

std::size_t peel_skin_slivers(TetMesh& mesh, const PostPassParams& p) { return SkinPeeler(mesh, p).run(); }

}  // namespace tactus::mesher
