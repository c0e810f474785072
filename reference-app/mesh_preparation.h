// A joined session's mesh made ready off the UI thread: its arrays adopted into a document
// (with their normals), its BVH built and copied for the session worker, its draw clusters
// built, and (through `finish`, which the app gives a GL context sharing its window's) its GL
// buffers filled. At 320K faces that is 100 ms and more, which on the UI thread made every
// artist's join a frame over 50 ms; the buffers alone were 346 ms at 1M vertices.
#pragma once

#include <csculpt.h>

#include <atomic>
#include <functional>
#include <string>
#include <thread>

#include "bvh.h"
#include "draw_clusters.h"
#include "mesh_buffers.h"
#include "mesh_document.h"

/** Everything a joined mesh needs before its first frame. */
struct PreparedMesh {
  MeshDocument document;
  TriangleBvh bvh;
  DrawClusters clusters;  // the renderer's, for document's positions and triangles
  // The session worker's own copy of `bvh`, and the positions it was fitted to.
  TriangleBvh worker_bvh;
  std::vector<float> worker_positions;
  MeshBuffers buffers;  // what `finish` filled for it, if anything
};

class MeshPreparation {
 public:
  /** Starts preparing `mesh` (owned from here; NULL fails with a message); `finish`, if
   *  given, runs last on the preparation's thread, on a prepared mesh. */
  explicit MeshPreparation(csc_mesh* mesh, std::function<void(PreparedMesh&)> finish = {});
  ~MeshPreparation();  // waits for the thread
  MeshPreparation(const MeshPreparation&) = delete;
  MeshPreparation& operator=(const MeshPreparation&) = delete;

  bool ready() const { return ready_.load(std::memory_order_acquire); }
  /** Once ready: moves the prepared mesh out; false with `error` when it failed. */
  bool take(PreparedMesh& out, std::string& error);

 private:
  void prepare();

  csc_mesh* mesh_;
  std::function<void(PreparedMesh&)> finish_;
  PreparedMesh prepared_;
  std::string error_;
  bool ok_ = false;
  std::atomic<bool> ready_{false};
  std::thread thread_;  // last: starts once everything above exists
};
