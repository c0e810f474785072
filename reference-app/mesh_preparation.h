// A joined session's mesh made ready off the UI thread: its arrays adopted into a document
// (with their normals), its BVH built and copied for the session worker, its draw clusters
// built. At 320K faces that is 100 ms and more, which on the UI thread made every artist's
// join a frame over 50 ms; the upload is all that is left there.
#pragma once

#include <csculpt.h>

#include <atomic>
#include <string>
#include <thread>

#include "bvh.h"
#include "draw_clusters.h"
#include "mesh_document.h"

/** Everything a joined mesh needs before its first frame. */
struct PreparedMesh {
  MeshDocument document;
  TriangleBvh bvh;
  DrawClusters clusters;  // the renderer's, for document's positions and triangles
  // The session worker's own copy of `bvh`, and the positions it was fitted to.
  TriangleBvh worker_bvh;
  std::vector<float> worker_positions;
};

class MeshPreparation {
 public:
  /** Starts preparing `mesh` (owned from here; NULL fails with a message). */
  explicit MeshPreparation(csc_mesh* mesh);
  ~MeshPreparation();  // waits for the thread
  MeshPreparation(const MeshPreparation&) = delete;
  MeshPreparation& operator=(const MeshPreparation&) = delete;

  bool ready() const { return ready_.load(std::memory_order_acquire); }
  /** Once ready: moves the prepared mesh out; false with `error` when it failed. */
  bool take(PreparedMesh& out, std::string& error);

 private:
  void prepare();

  csc_mesh* mesh_;
  PreparedMesh prepared_;
  std::string error_;
  bool ok_ = false;
  std::atomic<bool> ready_{false};
  std::thread thread_;  // last: starts once everything above exists
};
