// Soft-tissue wedges between bone (post_passes.hpp): a soft-tissue tet below the guarantees with
// two or more faces on one bone fills a notch of that bone's surface (where two bones meet and
// the tissue between them thins out to a sliver). Its nodes all lie on that bone's faces, so no
// relocation can enlarge it and no surface edge of it may be collapsed without moving a bone.
// Giving it to the bone keeps the bone's surface 2-manifold (the tet's four nodes are already on
// the two shared faces: the notch is filled, nothing touches at a single node or edge), moves no
// node, and costs the soft tissue the wedge's volume. It is done only when, measured against that
// bone's median, the tet meets the guarantees.
#include <map>

#include "tactus/core/contracts.hpp"
#include "tactus/mesher/post_passes.hpp"
#include "topology.hpp"

namespace tactus::mesher {

std::size_t give_wedges_to_bone(TetMesh& mesh, const PostPassParams& p) {
  const GuaranteeMeasure measure(mesh, p);
  FaceOwners owners = face_owners(mesh);
  std::size_t given = 0;
  for (std::size_t e = 0; e < mesh.tets.size(); ++e) {
    if (mesh.tet_group[e] != contracts::kSoftTissueLabel || measure(mesh, mesh.tets[e], mesh.tet_group[e]) >= 1) continue;
    std::map<int, int> bone_faces;  // bone label -> faces of e shared with it
    for (const auto& f : kFaces)
      for (std::size_t o : owners[tet_face(mesh.tets[e], f)])
        if (o != e && mesh.tet_group[o] >= contracts::kFirstBoneLabel) ++bone_faces[mesh.tet_group[o]];
    for (const auto& [bone, faces] : bone_faces)
      if (faces >= 2 && measure(mesh, mesh.tets[e], bone) >= 1.0 / p.guarantee_margin) {  // the guarantees themselves, without the margin
        mesh.tet_group[e] = bone;
        ++given;
        break;
      }
  }
  if (given > 0) rebuild_boundary_triangles(mesh);
  return given;
}

}  // namespace tactus::mesher
