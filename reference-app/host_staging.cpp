#include "host_staging.h"

#include <algorithm>
#include <chrono>
#include <utility>

void HostStaging::prepare(const MeshDocument& document, const TriangleBvh& bvh) {
  vertices_ = document.vertex_count();
  triangles_ = document.triangle_count();
  widths_.clear();
  std::vector<MeshChannel> channels;
  for (const MeshChannel& c : document.channels) {
    widths_.push_back(c.width);
    channels.push_back({c.name, c.width, c.linearisation, c.min_value, c.max_value, {}});
  }
  pending_ =
      std::async(std::launch::async,
                 [vertices = size_t{vertices_}, triangles = size_t{triangles_},
                  channels = std::move(channels), bvh_sizes = bvh.array_sizes()]() mutable {
                   HostCopy copy;  // resize() writes every value: each page is faulted in here
                   copy.content.positions.resize(3 * vertices);
                   copy.content.triangles.resize(3 * triangles);
                   for (MeshChannel& c : channels) c.values.resize(vertices * c.width);
                   copy.content.channels = std::move(channels);
                   copy.bvh = TriangleBvh::with_room_for(bvh_sizes);
                   return copy;
                 });
}

// Asked every frame out of a session: compares, allocates nothing.
bool HostStaging::prepared_for(const MeshDocument& document) const {
  return pending_.valid() && vertices_ == document.vertex_count() &&
         triangles_ == document.triangle_count() &&
         std::equal(widths_.begin(), widths_.end(), document.channels.begin(),
                    document.channels.end(),
                    [](uint32_t width, const MeshChannel& c) { return width == c.width; });
}

// Copy assignment keeps a vector's storage when it is large enough: the prepared pages.
HostCopy HostStaging::copy(const MeshDocument& document, const TriangleBvh& bvh) {
  HostCopy out;
  if (pending_.valid() && pending_.wait_for(std::chrono::seconds(0)) == std::future_status::ready)
    out = pending_.get();
  out.content.positions = document.positions;
  out.content.triangles = document.triangles;
  out.content.channels = document.channels;
  out.bvh = bvh;
  return out;
}
