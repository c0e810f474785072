// A joined session's mesh made ready off the UI thread: its arrays adopted into a document
// (with their normals) and its BVH built. At 320K faces that is 50 ms and more, which on the
// UI thread made every artist's join a frame over 50 ms; the upload is all that is left there.
#pragma once

#include <csculpt.h>

#include <atomic>
#include <string>
#include <thread>

#include "bvh.h"
#include "mesh_document.h"

class MeshPreparation {
 public:
  /** Starts preparing `mesh` (owned from here; NULL fails with a message). */
  explicit MeshPreparation(csc_mesh* mesh);
  ~MeshPreparation();  // waits for the thread
  MeshPreparation(const MeshPreparation&) = delete;
  MeshPreparation& operator=(const MeshPreparation&) = delete;

  bool ready() const { return ready_.load(std::memory_order_acquire); }
  /** Once ready: moves the document and its BVH out; false with `error` when it failed. */
  bool take(MeshDocument& document, TriangleBvh& bvh, std::string& error);

 private:
  void prepare();

  csc_mesh* mesh_;
  MeshDocument document_;
  TriangleBvh bvh_;
  std::string error_;
  bool ok_ = false;
  std::atomic<bool> ready_{false};
  std::thread thread_;  // last: starts once everything above exists
};
