#pragma once
// Face keys and the faces of a tet, for the post-passes.
#include <array>

namespace tactus::mesher {

std::array<int, 3> sorted_face(int a, int b, int c);
inline constexpr int kFaces[4][4] = {{1, 2, 3, 0}, {0, 2, 3, 1}, {0, 1, 3, 2}, {0, 1, 2, 3}};  // face nodes, then the opposite

}  // namespace tactus::mesher
