// Flips at the tets below the guarantees (post_passes.hpp). Relocation moves a surface node only
// within its surface, so a sliver whose four nodes lie on surfaces (flat on a bone, two of its
// edges crossing) stays flat however its nodes move, and it may have no short surface edge to
// collapse. Its connectivity has to change instead, inside one subdomain (no surface, interface
// or node changes; the outer faces of what is replaced stay faces of what replaces it):
//  - a 2-3 flip replaces two tets sharing a face (a, b, c), apexes q and p, by the three tets
//    (a, b, p, q), (b, c, p, q), (c, a, p, q) around the new edge pq; valid when pq crosses the
//    inside of the face;
//  - edge removal replaces the n tets around an interior edge ab (a ring r_0 .. r_{n-1} of
//    nodes around it) by 2 (n - 2) tets: a triangulation of the ring's polygon, each triangle
//    joined to a and to b (n = 3 is the 3-2 flip, n = 4 the 4-4 flip); the fans from each ring
//    node are tried. This is the flip that takes out a sliver whose long crossing edge is
//    interior (Shewchuk, "Two discrete optimization algorithms for the topological improvement
//    of tetrahedral meshes", 2002; Klingner & Shewchuk 2007).
// Validity: the new tets, each oriented positive, fill exactly the volume of the old ones (they
// overlap, adding up to more, when the new edge misses the face or a triangle of the ring's
// polygon does not separate a from b); no new edge or triangle may already be in the mesh. A flip is kept only when the
// worst guarantee measure of the new tets exceeds that of the old and no more of them are below it.
#include <algorithm>
#include <cmath>
#include <map>

#include "tactus/core/log.hpp"
#include "tactus/core/stable_step.hpp"
#include "tactus/mesher/post_passes.hpp"
#include "topology.hpp"

namespace tactus::mesher {

namespace {

constexpr int kDead = -1;  // the group of a slot a 3-2 flip emptied

class Flipper {
 public:
  Flipper(TetMesh& mesh, const PostPassParams& p) : mesh_(mesh), measure_(mesh, p), tets_of_(tets_around_nodes(mesh)), owners_(face_owners(mesh)) {}

  // Sweeps over the tets below the guarantees until a sweep flips nothing (at most `sweeps`).
  std::size_t run(int sweeps) {
    std::size_t flipped = 0;
    for (int sweep = 0; sweep < sweeps; ++sweep) {
      std::size_t now = 0;
      for (std::size_t e = 0; e < mesh_.tets.size(); ++e) {
        if (mesh_.tet_group[e] == kDead || measure(e) >= 1) continue;
        bool done = false;
        for (const auto& f : kFaces)
          if ((done = try_flip(e, tet_face(mesh_.tets[e], f)))) break;
        for (std::size_t i = 0; i < 4 && !done; ++i)
          for (std::size_t j = i + 1; j < 4 && !done; ++j) done = try_remove_edge(mesh_.tets[e][i], mesh_.tets[e][j]);
        now += done;
      }
      flipped += now;
      if (now == 0) break;
    }
    return flipped;
  }

 private:
  double measure(std::size_t e) const { return measure_(mesh_, mesh_.tets[e], mesh_.tet_group[e]); }
  double volume(const std::array<int, 4>& t) const {
    const auto x = [&](int v) -> const Vec3& { return mesh_.nodes[static_cast<std::size_t>(v)]; };
    return tet_volume(x(t[0]), x(t[1]), x(t[2]), x(t[3]));
  }

  void add_faces(std::size_t e) {
    for (const auto& f : kFaces) owners_[tet_face(mesh_.tets[e], f)].push_back(e);
  }
  void remove_faces(std::size_t e) {
    for (const auto& f : kFaces) {
      auto it = owners_.find(tet_face(mesh_.tets[e], f));
      it->second.erase(std::find(it->second.begin(), it->second.end(), e));
      if (it->second.empty()) owners_.erase(it);
    }
  }

  static int apex(const std::array<int, 4>& t, const std::array<int, 3>& face) {
    for (int v : t)
      if (v != face[0] && v != face[1] && v != face[2]) return v;
    return -1;
  }

  bool edge_exists(int p, int q) const {
    for (std::size_t o : tets_of_[static_cast<std::size_t>(p)])
      if (std::count(mesh_.tets[o].begin(), mesh_.tets[o].end(), q)) return true;
    return false;
  }

  bool try_flip(std::size_t e, const std::array<int, 3>& face) {
    const auto it = owners_.find(face);
    if (it == owners_.end() || it->second.size() != 2) return false;  // a boundary face
    const std::size_t f = it->second[0] == e ? it->second[1] : it->second[0];
    const int group = mesh_.tet_group[e];
    if (mesh_.tet_group[f] != group) return false;  // an interface: it must stay
    const int q = apex(mesh_.tets[e], face), p = apex(mesh_.tets[f], face);
    if (edge_exists(p, q)) return false;
    // pq crosses the inside of the face exactly when the three tets it makes with the face's
    // edges fill the pair: their volumes (each oriented positive) add up to the pair's. Where pq
    // passes outside the face they overlap and add up to more.
    const double pair = std::abs(volume(mesh_.tets[e])) + std::abs(volume(mesh_.tets[f]));
    const double old_worst = std::min(measure(e), measure(f));
    const std::size_t old_poor = (measure(e) < 1) + (measure(f) < 1);
    std::array<std::array<int, 4>, 3> made;
    double filled = 0, new_worst = 1e300;
    std::size_t new_poor = 0;
    for (std::size_t k = 0; k < 3; ++k) {
      std::array<int, 4>& t = made[k];
      t = {face[k], face[(k + 1) % 3], q, p};
      const double v = volume(t);
      if (v == 0) return false;
      if (v < 0) std::swap(t[2], t[3]);
      filled += std::abs(v);
      const double m = measure_(mesh_, t, group);
      new_worst = std::min(new_worst, m), new_poor += m < 1;
    }
    if (!(pair > 0) || filled > pair * (1 + 1e-9)) return false;
    if (new_worst <= old_worst * (1 + 1e-9) || new_poor > old_poor) return false;
    replace({e, f}, {made.begin(), made.end()}, group);
    return true;
  }

  // The tets around edge ab, when they are all of one subdomain and close a ring around it; the
  // ring's nodes in order (each consecutive pair and the edge make one of the tets).
  bool ring_around(int a, int b, std::vector<std::size_t>& around, std::vector<int>& ring) const {
    around.clear(), ring.clear();
    for (std::size_t o : tets_of_[static_cast<std::size_t>(a)])
      if (std::count(mesh_.tets[o].begin(), mesh_.tets[o].end(), b)) around.push_back(o);
    if (around.size() < 3 || around.size() > 7) return false;
    const int group = mesh_.tet_group[around[0]];
    std::vector<std::array<int, 2>> rims;  // per tet its two nodes off the edge
    for (std::size_t o : around) {
      if (mesh_.tet_group[o] != group) return false;
      std::array<int, 2> rim{};
      int k = 0;
      for (int v : mesh_.tets[o])
        if (v != a && v != b) rim[static_cast<std::size_t>(k++)] = v;
      rims.push_back(rim);
    }
    // Chain the rims into one cycle; an edge on a surface leaves an open chain (false).
    std::vector<char> used(rims.size(), 0);
    ring.push_back(rims[0][0]);
    int next = rims[0][1];
    used[0] = 1;
    for (std::size_t step = 1; step < rims.size(); ++step) {
      ring.push_back(next);
      bool found = false;
      for (std::size_t r = 0; r < rims.size() && !found; ++r)
        if (!used[r] && (rims[r][0] == next || rims[r][1] == next)) {
          next = rims[r][0] == next ? rims[r][1] : rims[r][0];
          used[r] = 1, found = true;
        }
      if (!found) return false;
    }
    return next == ring[0];
  }

  bool try_remove_edge(int a, int b) {
    std::vector<std::size_t> around;
    std::vector<int> ring;
    if (!ring_around(a, b, around, ring)) return false;
    const int group = mesh_.tet_group[around[0]];
    double old_volume = 0, old_worst = 1e300;
    std::size_t old_poor = 0;
    for (std::size_t o : around) {
      old_volume += std::abs(volume(mesh_.tets[o]));
      const double m = measure(o);
      old_worst = std::min(old_worst, m), old_poor += m < 1;
    }
    const std::size_t n = ring.size();
    std::vector<std::array<int, 4>> best;
    double best_worst = old_worst * (1 + 1e-9);
    for (std::size_t apex = 0; apex < n; ++apex) {  // the fan of diagonals from ring[apex]
      bool valid = true;
      for (std::size_t k = 2; k + 1 < n && valid; ++k) valid = !edge_exists(ring[apex], ring[(apex + k) % n]);
      if (!valid) continue;
      std::vector<std::array<int, 4>> made;
      double filled = 0, worst = 1e300;
      std::size_t poor = 0;
      for (std::size_t k = 1; k + 1 < n && valid; ++k) {
        const int u = ring[apex], v = ring[(apex + k) % n], w = ring[(apex + k + 1) % n];
        if (owners_.count(sorted_face(u, v, w))) {  // a 3-2 flip's triangle already a face elsewhere
          valid = false;
          break;
        }
        for (const int tip : {a, b}) {
          std::array<int, 4> t{u, v, w, tip};
          const double vol = volume(t);
          if (vol == 0) {
            valid = false;
            break;
          }
          if (vol < 0) std::swap(t[2], t[3]);
          filled += std::abs(vol);
          const double m = measure_(mesh_, t, group);
          worst = std::min(worst, m), poor += m < 1;
          made.push_back(t);
        }
      }
      if (!valid || filled > old_volume * (1 + 1e-9) || poor > old_poor || worst <= best_worst) continue;
      best = std::move(made), best_worst = worst;
    }
    if (best.empty()) return false;
    replace(around, best, group);
    return true;
  }

  // The tets `gone` replaced by `made` (of `group`): made reuses their slots, appends what does
  // not fit, and a 3-2 flip's spare slot is marked dead (skipped, then removed by compact()).
  void replace(const std::vector<std::size_t>& gone, const std::vector<std::array<int, 4>>& made, int group) {
    for (std::size_t o : gone) {
      remove_faces(o);
      for (int v : mesh_.tets[o]) std::erase(tets_of_[static_cast<std::size_t>(v)], o);
    }
    std::vector<std::size_t> slots(gone.begin(), gone.end());
    for (std::size_t k = slots.size(); k < made.size(); ++k) {
      slots.push_back(mesh_.tets.size());
      mesh_.tets.push_back({});
      mesh_.tet_group.push_back(group);
    }
    for (std::size_t k = 0; k < made.size(); ++k) {
      mesh_.tets[slots[k]] = made[k];
      add_faces(slots[k]);
      for (int v : made[k]) tets_of_[static_cast<std::size_t>(v)].push_back(slots[k]);
    }
    for (std::size_t k = made.size(); k < slots.size(); ++k) mesh_.tet_group[slots[k]] = kDead, dead_.push_back(slots[k]);
  }

 public:
  // Removes the dead slots, highest first, each by moving the last tet into it (the last is alive:
  // every dead slot above it has gone already).
  void compact() {
    std::sort(dead_.rbegin(), dead_.rend());
    for (std::size_t slot : dead_) {
      mesh_.tets[slot] = mesh_.tets.back(), mesh_.tet_group[slot] = mesh_.tet_group.back();
      mesh_.tets.pop_back(), mesh_.tet_group.pop_back();
    }
    dead_.clear();
  }

 private:
  TetMesh& mesh_;
  GuaranteeMeasure measure_;
  std::vector<std::vector<std::size_t>> tets_of_;
  FaceOwners owners_;
  std::vector<std::size_t> dead_;  // slots emptied by 3-2 flips
};

}  // namespace

std::size_t flip_poor_tets(TetMesh& mesh, const PostPassParams& p) {
  Flipper flipper(mesh, p);
  const std::size_t flipped = flipper.run(4);
  flipper.compact();
  log::debug() << "mesher: " << flipped << " flips at tets below the guarantees";
  return flipped;
}

}  // namespace tactus::mesher
