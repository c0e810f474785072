// The GL buffers of one mesh, by name: made where a GL context is current (renderer.h), handed
// between threads without GL headers (mesh_preparation.h).
#pragma once

struct MeshBuffers {
  unsigned index = 0;           // 0: no buffers
  unsigned attributes[5] = {};  // position, normal, albedo, roughness, metallic
};
