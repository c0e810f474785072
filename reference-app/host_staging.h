// Memory for hosting's copies of the document's arrays and of the BVH, allocated and first
// touched on a thread of its own. The copies are taken on the UI thread when Host is clicked
// (the artist sculpts on while the worker creates the session), and copying into new memory
// is mostly the kernel faulting in and zeroing each page: at 2M faces the arrays took 157 ms
// and the BVH 255 ms, at 320K 25 and 34 ms. Into pages touched beforehand they take a few
// milliseconds. The price is a second copy of both, held while the artist is not in a session.
#pragma once

#include <future>
#include <vector>

#include "bvh.h"
#include "mesh_document.h"

/** What hosting hands the session worker: the document's arrays and the UI's BVH (tight over
 *  the same positions). */
struct HostCopy {
  MeshContent content;
  TriangleBvh bvh;
};

class HostStaging {
 public:
  /** Starts allocating, on another thread, memory shaped like the document's arrays and `bvh`
   *  (a preparation still running for an earlier shape is waited for first). */
  void prepare(const MeshDocument& document, const TriangleBvh& bvh);
  /** Memory is being prepared, or ready, for arrays of the document's shape. */
  bool prepared_for(const MeshDocument& document) const;
  void wait() const {
    if (pending_.valid()) pending_.wait();
  }
  /** The document's arrays and `bvh`, copied into the prepared memory if it is ready, else
   *  into new memory. */
  HostCopy copy(const MeshDocument& document, const TriangleBvh& bvh);

 private:
  std::future<HostCopy> pending_;
  // The shape pending_ is being made for: vertices, triangles, each channel's width (the BVH
  // is built once per shape).
  uint32_t vertices_ = 0, triangles_ = 0;
  std::vector<uint32_t> widths_;
};
