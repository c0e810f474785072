// The C-ABI tests' host: its own copy of a mesh's vertex arrays, handed to the library as
// csc_vertex_arrays the way a DCC tool hands over its buffers.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <vector>

#include "csculpt.h"

/// The host's copy of a mesh's vertex arrays (positions and every channel, base order).
struct HostArrays {
  explicit HostArrays(const csc_mesh* mesh) {
    const std::uint32_t n = csc_mesh_vertex_count(mesh);
    positions.assign(csc_mesh_positions(mesh), csc_mesh_positions(mesh) + 3 * n);
    for (std::uint32_t c = 0; c < csc_mesh_channel_count(mesh); ++c) {
      csc_channel_view v = CSC_CHANNEL_VIEW_INIT;
      EXPECT_EQ(csc_mesh_channel(mesh, c, &v), CSC_OK);
      channels.emplace_back(v.values, v.values + std::size_t{n} * v.desc.width);
      widths.push_back(v.desc.width);
    }
    refresh();
  }
  HostArrays(const HostArrays& o) : positions(o.positions), channels(o.channels), widths(o.widths) {
    refresh();
  }
  HostArrays& operator=(const HostArrays&) = delete;
  void refresh() {
    pointers.clear();
    for (auto& c : channels) pointers.push_back(c.data());
  }
  csc_vertex_arrays arrays() {
    csc_vertex_arrays a = CSC_VERTEX_ARRAYS_INIT;
    a.vertex_count = static_cast<std::uint32_t>(positions.size() / 3);
    a.positions = positions.data();
    a.channel_count = static_cast<std::uint32_t>(channels.size());
    a.channels = pointers.empty() ? nullptr : pointers.data();
    return a;
  }
  bool operator==(const HostArrays& o) const {
    return positions.size() == o.positions.size() && channels.size() == o.channels.size() &&
           std::memcmp(positions.data(), o.positions.data(), positions.size() * 4) == 0 &&
           std::equal(channels.begin(), channels.end(), o.channels.begin(),
                      [](const std::vector<float>& a, const std::vector<float>& b) {
                        return a.size() == b.size() &&
                               std::memcmp(a.data(), b.data(), a.size() * 4) == 0;
                      });
  }

  std::vector<float> positions;
  std::vector<std::vector<float>> channels;
  std::vector<std::uint32_t> widths;
  std::vector<float*> pointers;
};
