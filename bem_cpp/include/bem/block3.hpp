#pragma once
// The 3 x 3 blocks of the 3D Lame assemblies (lame_surface.cpp, lame_surface_entries.cpp):
// a node pair's block of a matrix with node-major dofs, the cross-product matrix of a
// surface curl and the product of two blocks.
#include "bem/vec3.hpp"

namespace bem {

using Block = double[3][3];

/// [c]_x: the matrix of w -> c x w.
inline void cross_matrix(Vec3 c, Block& A) {
  A[0][0] = A[1][1] = A[2][2] = 0.0;
  A[0][1] = -c.z;
  A[0][2] = c.y;
  A[1][0] = c.z;
  A[1][2] = -c.x;
  A[2][0] = -c.y;
  A[2][1] = c.x;
}

/// C = A B.
inline void product(const Block& A, const Block& B, Block& C) {
  for (int k = 0; k < 3; ++k)
    for (int l = 0; l < 3; ++l) C[k][l] = A[k][0] * B[0][l] + A[k][1] * B[1][l] + A[k][2] * B[2][l];
}

}  // namespace bem
