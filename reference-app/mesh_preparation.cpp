#include "mesh_preparation.h"

#include <utility>

MeshPreparation::MeshPreparation(csc_mesh* mesh, std::function<void(PreparedMesh&)> finish)
    : mesh_(mesh), finish_(std::move(finish)), thread_([this] { prepare(); }) {}

MeshPreparation::~MeshPreparation() {
  if (thread_.joinable()) thread_.join();
  if (mesh_) csc_mesh_destroy(mesh_);
}

void MeshPreparation::prepare() {
  if (!mesh_)
    error_ = "cannot take the session's mesh";
  else
    ok_ = prepared_.document.adopt(mesh_, "session mesh", error_);
  if (ok_) {
    const MeshDocument& d = prepared_.document;
    prepared_.bvh.build(d.positions, d.triangles);
    prepared_.clusters.build(d.positions, d.triangles);
    prepared_.worker_bvh = prepared_.bvh;
    prepared_.worker_positions = d.positions;
    if (finish_) finish_(prepared_);
  }
  ready_.store(true, std::memory_order_release);
}

bool MeshPreparation::take(PreparedMesh& out, std::string& error) {
  thread_.join();
  if (!ok_) {
    error = error_;
    return false;
  }
  out = std::move(prepared_);
  return true;
}
