#include "mesh_preparation.h"

#include <utility>

MeshPreparation::MeshPreparation(csc_mesh* mesh) : mesh_(mesh), thread_([this] { prepare(); }) {}

MeshPreparation::~MeshPreparation() {
  if (thread_.joinable()) thread_.join();
  if (mesh_) csc_mesh_destroy(mesh_);
}

void MeshPreparation::prepare() {
  if (!mesh_)
    error_ = "cannot take the session's mesh";
  else
    ok_ = document_.adopt(mesh_, "session mesh", error_);
  if (ok_) bvh_.build(document_.positions, document_.triangles);
  ready_.store(true, std::memory_order_release);
}

bool MeshPreparation::take(MeshDocument& document, TriangleBvh& bvh, std::string& error) {
  thread_.join();
  if (!ok_) {
    error = error_;
    return false;
  }
  document = std::move(document_);
  bvh = std::move(bvh_);
  return true;
}
