// Non-manifold boundaries resolved on the tets (post_passes.hpp). The labels are made
// well-composed before meshing and CGAL's manifold criterion refines the surface facets until each
// boundary is a 2-manifold, but that criterion does not always finish (on a real label volume it
// can ask for millions of vertices, and the mesh is then made without it), and a boundary can
// still pinch where a Delaunay facet cuts a thin part. What is left is resolved here, where the
// defect is: the tets around a non-manifold edge (its ring) or vertex (its star) of one boundary
// (the skin: every live tet is inside it; a group's own boundary: its tets are) split into more
// than one face-connected run of inside tets. Either a run of inside tets leaves the boundary
// (relabelled to the label it shares the most faces with, or removed where it only touches the
// outside) or a run of outside tets joins it (the pair made face-connected), whichever moves the
// least volume - the tet counterpart of the voxel rule of well_composed.hpp. A change is kept only
// when it lowers the defects counted around it (every boundary through the nodes of the ring or
// star), empties no group, removes no node's last tet, and gives no tet a length below the length
// guarantee of its new group. No node moves, so no tet's shape changes.
#include <algorithm>
#include <map>
#include <numeric>
#include <set>

#include "tactus/core/log.hpp"
#include "tactus/core/stable_step.hpp"
#include "tactus/mesher/post_passes.hpp"
#include "topology.hpp"

namespace tactus::mesher {

namespace {

using Face = std::array<int, 3>;
constexpr int kSkin = -1;  // the boundary id of the skin (groups are their tags)

class PinchResolver {
 public:
  PinchResolver(TetMesh& mesh, const PostPassParams& p)
      : mesh_(mesh), p_(p), alive_(mesh.tets.size(), 1), tets_of_(tets_around_nodes(mesh)), owners_(face_owners(mesh)), measure_(mesh, p) {
    for (int g : mesh.tet_group) ++group_tets_[g];
  }

  BoundaryPinchReport run() {
    BoundaryPinchReport r;
    std::vector<Defect> found = defects();
    r.defects_before = found.size();
    for (int round = 0; round < 8 && !found.empty(); ++round) {
      std::size_t changed = 0;
      for (const auto& d : found) changed += resolve(d, r);
      if (changed == 0) break;
      found = defects();
    }
    r.defects_after = found.size();
    if (r.tets_relabelled + r.tets_removed > 0) keep_alive_tets(mesh_, alive_);
    return r;
  }

 private:
  struct Defect {
    int boundary;  // kSkin or a group
    int a, b;      // an edge (a, b), or the vertex a (b = -1)
  };

  bool inside(std::size_t e, int boundary) const { return alive_[e] && (boundary == kSkin || mesh_.tet_group[e] == boundary); }

  // A face is on a boundary when exactly one of its live tets is inside it.
  bool on_boundary(const Face& f, int boundary) const {
    int in = 0;
    for (std::size_t e : owners_.at(f)) in += inside(e, boundary);
    return in == 1;
  }

  // The faces of `boundary` through node v.
  std::vector<Face> boundary_faces_at(int v, int boundary) const {
    std::set<Face> faces;
    for (std::size_t e : tets_of_[static_cast<std::size_t>(v)])
      if (alive_[e])
        for (const auto& f : kFaces) {
          const Face key = tet_face(mesh_.tets[e], f);
          if (std::find(key.begin(), key.end(), v) != key.end() && on_boundary(key, boundary)) faces.insert(key);
        }
    return {faces.begin(), faces.end()};
  }

  // The defects of `boundary` at node v: its edges (v, w) in other than two of the boundary's
  // faces, and v itself when its faces form more than one fan (as boundary_topology counts them).
  std::size_t defects_at(int v, int boundary, std::vector<Defect>* out = nullptr) const {
    const std::vector<Face> faces = boundary_faces_at(v, boundary);
    std::map<int, int> edge_faces;
    for (const Face& f : faces)
      for (int w : f)
        if (w != v) ++edge_faces[w];
    std::size_t n = 0;
    for (const auto& [w, count] : edge_faces)
      if (count != 2) {
        ++n;
        if (out && v < w) out->push_back({boundary, v, w});
      }
    const std::vector<std::size_t> fan = face_fans(faces);
    const std::size_t fans_at_v = fan.empty() ? 0 : *std::max_element(fan.begin(), fan.end()) + 1;
    if (fans_at_v > 1) {
      ++n;
      if (out) out->push_back({boundary, v, -1});
    }
    return n;
  }

  // The boundaries through node v: the skin and the groups of its live tets.
  std::set<int> boundaries_at(int v) const {
    std::set<int> b{kSkin};
    for (std::size_t e : tets_of_[static_cast<std::size_t>(v)])
      if (alive_[e]) b.insert(mesh_.tet_group[e]);
    return b;
  }

  std::size_t local_defects(const std::set<int>& nodes, const std::set<int>& boundaries) const {
    std::size_t n = 0;
    for (int v : nodes)
      for (int b : boundaries) n += defects_at(v, b);
    return n;
  }

  std::vector<Defect> defects() const {
    std::vector<Defect> out;
    for (std::size_t v = 0; v < mesh_.nodes.size(); ++v)
      for (int b : boundaries_at(static_cast<int>(v))) defects_at(static_cast<int>(v), b, &out);
    return out;
  }

  // The live tets through the defect (its edge's ring or its vertex's star), split into
  // face-connected runs of inside and of outside tets (joined through faces holding the defect).
  void runs(const Defect& d, std::vector<std::vector<std::size_t>>& in, std::vector<std::vector<std::size_t>>& out) const {
    std::vector<std::size_t> star;
    for (std::size_t e : tets_of_[static_cast<std::size_t>(d.a)]) {
      const auto& t = mesh_.tets[e];
      if (alive_[e] && (d.b < 0 || std::find(t.begin(), t.end(), d.b) != t.end())) star.push_back(e);
    }
    std::vector<std::size_t> parent(star.size());
    std::iota(parent.begin(), parent.end(), 0);
    const auto root = [&](std::size_t i) {
      while (parent[i] != i) i = parent[i] = parent[parent[i]];
      return i;
    };
    std::map<Face, std::size_t> seen;  // a face holding the defect -> the first star tet on it
    for (std::size_t i = 0; i < star.size(); ++i)
      for (const auto& f : kFaces) {
        const Face key = tet_face(mesh_.tets[star[i]], f);
        const auto holds = [&](int x) { return x < 0 || std::find(key.begin(), key.end(), x) != key.end(); };
        if (!holds(d.a) || !holds(d.b)) continue;
        const auto [it, first] = seen.emplace(key, i);
        if (!first && inside(star[it->second], d.boundary) == inside(star[i], d.boundary)) parent[root(i)] = root(it->second);
      }
    std::map<std::size_t, std::vector<std::size_t>> groups;
    for (std::size_t i = 0; i < star.size(); ++i) groups[root(i)].push_back(star[i]);
    for (auto& [r, tets] : groups) (inside(tets[0], d.boundary) ? in : out).push_back(std::move(tets));
  }

  // A tunnel through the body closing at vertex v (its tets one run, the void around it in two
  // parts, so the skin's faces there form two fans): the shortest path of tets through the star,
  // joined through faces holding v, from a tet on one fan to a tet on another. Removing it opens
  // the tunnel to one side.
  std::vector<std::size_t> bridge(int v) const {
    const std::vector<Face> faces = boundary_faces_at(v, kSkin);
    const std::vector<std::size_t> fan = face_fans(faces);
    std::map<std::size_t, std::size_t> fan_of;  // star tet -> its skin face's fan
    for (std::size_t i = 0; i < faces.size(); ++i)
      for (std::size_t e : owners_.at(faces[i]))
        if (alive_[e]) fan_of.emplace(e, fan[i]);
    std::map<std::size_t, std::size_t> from;  // breadth-first search from the first fan's tets
    std::vector<std::size_t> queue;
    for (const auto& [e, f] : fan_of)
      if (f == 0) from.emplace(e, e), queue.push_back(e);
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const std::size_t e = queue[head];
      if (fan_of.count(e) && fan_of.at(e) != 0) {
        std::vector<std::size_t> path{e};
        while (from.at(path.back()) != path.back()) path.push_back(from.at(path.back()));
        return path;
      }
      for (const auto& f : kFaces) {
        const Face key = tet_face(mesh_.tets[e], f);
        if (std::find(key.begin(), key.end(), v) == key.end()) continue;
        for (std::size_t o : owners_.at(key))
          if (alive_[o] && from.emplace(o, e).second) queue.push_back(o);
      }
    }
    return {};
  }

  // Whether a tet of these runs has a face on the skin.
  bool touches_void(const std::vector<std::vector<std::size_t>>& runs) const {
    for (const auto& run : runs)
      for (std::size_t e : run)
        for (const auto& f : kFaces)
          if (on_boundary(tet_face(mesh_.tets[e], f), kSkin)) return true;
    return false;
  }

  // The label a run leaving `boundary` goes to: the one its tets share the most faces with among
  // live tets of other labels (-1: only the outside; the run is removed).
  int destination(const std::vector<std::size_t>& run, int boundary) const {
    std::map<int, int> shared;
    for (std::size_t e : run)
      for (const auto& f : kFaces)
        for (std::size_t o : owners_.at(tet_face(mesh_.tets[e], f)))
          if (o != e && alive_[o] && std::find(run.begin(), run.end(), o) == run.end() && !inside(o, boundary)) ++shared[mesh_.tet_group[o]];
    int best = -1, most = 0;
    for (const auto& [label, n] : shared)
      if (n > most) best = label, most = n;
    return best;
  }

  double volume(const std::vector<std::size_t>& run) const {
    double v = 0;
    for (std::size_t e : run) {
      const auto& t = mesh_.tets[e];
      v += tet_volume(mesh_.nodes[static_cast<std::size_t>(t[0])], mesh_.nodes[static_cast<std::size_t>(t[1])],
                      mesh_.nodes[static_cast<std::size_t>(t[2])], mesh_.nodes[static_cast<std::size_t>(t[3])]);
    }
    return v;
  }

  // Whether every tet of `run` may take label `to` (-1: be removed).
  bool allowed(const std::vector<std::size_t>& run, int to) const {
    std::map<int, std::size_t> leaving;
    for (std::size_t e : run) ++leaving[mesh_.tet_group[e]];
    for (const auto& [g, n] : leaving)
      if (g != to && n >= group_tets_.at(g)) return false;  // a group emptied
    if (to >= 0) {
      for (std::size_t e : run)
        if (mesh_.tet_group[e] != to && measure_.length_ratio(mesh_, mesh_.tets[e], to) < p_.guarantee_length_ratio) return false;
      return true;
    }
    for (std::size_t e : run)  // removed: every node keeps a live tet outside the run
      for (int v : mesh_.tets[e]) {
        bool kept = false;
        for (std::size_t o : tets_of_[static_cast<std::size_t>(v)]) kept = kept || (alive_[o] && std::find(run.begin(), run.end(), o) == run.end());
        if (!kept) return false;
      }
    return true;
  }

  // Gives `run` label `to` (-1: removes it); returns the previous labels to undo it.
  std::vector<int> apply(const std::vector<std::size_t>& run, int to) {
    std::vector<int> before;
    for (std::size_t e : run) {
      before.push_back(mesh_.tet_group[e]);
      --group_tets_[mesh_.tet_group[e]];
      if (to < 0) {
        alive_[e] = 0;
      } else {
        mesh_.tet_group[e] = to;
        ++group_tets_[to];
      }
    }
    return before;
  }
  void undo(const std::vector<std::size_t>& run, int to, const std::vector<int>& before) {
    for (std::size_t i = 0; i < run.size(); ++i) {
      if (to < 0)
        alive_[run[i]] = 1;
      else
        --group_tets_[to];
      mesh_.tet_group[run[i]] = before[i];
      ++group_tets_[before[i]];
    }
  }

  // Tries every run's move at a defect that is still there; keeps the one that lowers the defects
  // around it moving the least volume. Returns 1 when a change was kept.
  std::size_t resolve(const Defect& d, BoundaryPinchReport& r) {
    std::vector<Defect> still;
    defects_at(d.a, d.boundary, &still);
    if (std::none_of(still.begin(), still.end(), [&](const Defect& s) { return s.b == d.b; })) return 0;
    std::vector<std::vector<std::size_t>> in, out;
    runs(d, in, out);
    std::set<int> nodes, boundaries{kSkin};
    for (const auto* side : {&in, &out})
      for (const auto& run : *side)
        for (std::size_t e : run)
          for (int v : mesh_.tets[e]) nodes.insert(v);
    for (int v : nodes)
      for (int b : boundaries_at(v)) boundaries.insert(b);
    const std::size_t now = local_defects(nodes, boundaries);
    struct Move {
      const std::vector<std::size_t>* run;
      int to;
      double volume;
    };
    std::vector<Move> moves;
    if (in.size() > 1)
      for (const auto& run : in) moves.push_back({&run, d.boundary == kSkin ? -1 : destination(run, d.boundary), volume(run)});
    // The void counts as one more outside run where the ring or star reaches the skin (a label
    // pinched against the skin, or wrapped around a run of another label there).
    if (out.size() + (touches_void(in) || touches_void(out)) > 1 && d.boundary != kSkin)
      for (const auto& run : out) moves.push_back({&run, d.boundary, volume(run)});
    std::sort(moves.begin(), moves.end(), [](const Move& x, const Move& y) { return x.volume < y.volume; });
    const std::vector<std::size_t> tunnel = d.boundary == kSkin && d.b < 0 && in.size() == 1 ? bridge(d.a) : std::vector<std::size_t>{};
    if (!tunnel.empty()) moves.push_back({&tunnel, -1, volume(tunnel)});
    // Then single tets, smallest first: where the outside's part is the void (a label pinched
    // against the skin, a tunnel through the body closing at a vertex) the runs of tets alone do
    // not show the pinch, but one tet of the ring or star opens it.
    std::vector<std::vector<std::size_t>> singles;
    for (const auto* side : {&in, &out})
      for (const auto& run : *side)
        for (std::size_t e : run) singles.push_back({e});
    std::vector<Move> single_moves;
    for (const auto& one : singles) {
      const bool is_in = inside(one[0], d.boundary);
      const int to = d.boundary == kSkin ? -1 : is_in ? destination(one, d.boundary) : d.boundary;
      if (!(d.boundary == kSkin && !is_in)) single_moves.push_back({&one, to, volume(one)});
    }
    std::sort(single_moves.begin(), single_moves.end(), [](const Move& x, const Move& y) { return x.volume < y.volume; });
    moves.insert(moves.end(), single_moves.begin(), single_moves.end());
    for (const Move& m : moves) {
      const bool ok = allowed(*m.run, m.to);
      log::debug() << "pinch: boundary " << d.boundary << " at " << d.a << "-" << d.b << ": " << in.size() << " inside runs, " << out.size()
                   << " outside; move of " << m.run->size() << " tets to " << m.to << (ok ? "" : " not allowed");
      if (!ok) continue;
      const std::vector<int> before = apply(*m.run, m.to);
      const std::size_t after = local_defects(nodes, boundaries);
      log::debug() << "pinch:   defects around " << now << " -> " << after;
      // The tunnel's bridge may leave as many defects as it takes, at other places: kept when the
      // tunnel vertex itself is resolved (removals only shrink the body, so this cannot cycle;
      // the next round sees the new defects).
      const bool bridged = m.run == &tunnel && after == now && defects_at(d.a, kSkin) == 0;
      if (after < now || bridged) {
        (m.to < 0 ? r.tets_removed : r.tets_relabelled) += m.run->size();
        r.volume_moved_m3 += m.volume;
        return 1;
      }
      undo(*m.run, m.to, before);
    }
    return 0;
  }

  TetMesh& mesh_;
  const PostPassParams& p_;
  std::vector<char> alive_;
  std::vector<std::vector<std::size_t>> tets_of_;
  FaceOwners owners_;
  GuaranteeMeasure measure_;
  std::map<int, std::size_t> group_tets_;
};

}  // namespace

BoundaryPinchReport resolve_boundary_pinches(TetMesh& mesh, const PostPassParams& p) { return PinchResolver(mesh, p).run(); }

}  // namespace tactus::mesher
