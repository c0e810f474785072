#include "attribution.h"

#include <algorithm>
#include <cmath>
#include <iterator>

#include "csculpt/error.h"
#include "csculpt/peer/session.h"
#include "csculpt/varint.h"

namespace csculpt::peer {

std::vector<std::uint32_t> touched(const Diff& d) {
  std::vector<std::uint32_t> all(d.positions.indices);
  for (const ChannelDiff& c : d.channels) {
    std::vector<std::uint32_t> merged;
    merged.reserve(all.size() + c.change.indices.size());
    std::set_union(all.begin(), all.end(), c.change.indices.begin(), c.change.indices.end(),
                   std::back_inserter(merged));
    all.swap(merged);
  }
  return all;
}

std::vector<float> change_amounts(const Diff& d, const Mesh& base,
                                  std::span<const std::uint32_t> vertices, float scale) {
  std::vector<float> amount(vertices.size(), 0.f);
  // Every index list is increasing and a subset of `vertices`: one cursor walks each.
  std::size_t at = 0;
  auto slot = [&](std::uint32_t v) {
    while (vertices[at] < v) ++at;
    return at;
  };
  for (std::size_t i = 0; i < d.positions.indices.size(); ++i) {
    const std::uint32_t v = d.positions.indices[i];
    const Vec3f& b = base.positions[v];
    const float* e = d.positions.values.data() + 3 * i;
    const float dx = e[0] - b.x, dy = e[1] - b.y, dz = e[2] - b.z;
    amount[slot(v)] += std::sqrt(dx * dx + dy * dy + dz * dz) / scale;
  }
  for (const ChannelDiff& c : d.channels) {
    const int k = base.find_channel(c.desc.name);
    if (k < 0) continue;
    const auto& values = base.channels[static_cast<std::size_t>(k)].values;
    const std::uint32_t w = c.desc.width;
    at = 0;
    for (std::size_t i = 0; i < c.change.indices.size(); ++i) {
      const std::uint32_t v = c.change.indices[i];
      float sum = 0;
      for (std::uint32_t j = 0; j < w; ++j)
        sum += std::abs(c.change.values[i * w + j] - values[std::size_t{v} * w + j]);
      amount[slot(v)] += sum;
    }
  }
  return amount;
}

Contribution measure_contribution(PeerId peer, const Diff& d, const Mesh& base,
                                  std::span<const std::uint32_t> vertices, float scale) {
  const std::vector<float> amount = change_amounts(d, base, vertices, scale);
  const float peak = amount.empty() ? 0.f : *std::max_element(amount.begin(), amount.end());
  Contribution c;
  c.peer = peer;
  c.scale = peak;
  put_index_gaps(vertices, c.index_gaps);
  for (const float a : amount)
    c.amounts.push_back(peak > 0 ? static_cast<std::uint8_t>(std::lround(a / peak * 255.f)) : 0);
  return c;
}

void add_contribution(const Contribution& c, std::vector<float>& into) {
  IndexGapReader indices(c.index_gaps.data(), c.index_gaps.size(), "attribution");
  try {
    for (std::size_t i = 0; i < c.amounts.size() && !indices.done(); ++i)
      into[indices.next(into.size())] += float(c.amounts[i]) / 255.f * c.scale;
  } catch (const InvalidInput&) {
    // cut here: the values added so far stay
  }
}

std::array<float, 3> peer_colour(std::size_t rank) {
  // green, blue, red, magenta, orange, teal, yellow, violet: green + blue mix to cyan (Fig. 1)
  static const std::array<float, 3> hues[8] = {
      {0.1f, 0.85f, 0.2f},  {0.15f, 0.35f, 0.95f}, {0.9f, 0.15f, 0.1f}, {0.85f, 0.2f, 0.8f},
      {0.95f, 0.55f, 0.1f}, {0.1f, 0.6f, 0.6f},    {0.9f, 0.85f, 0.1f}, {0.5f, 0.3f, 0.85f}};
  return hues[rank % 8];
}

std::vector<float> attribution_colours(
    const std::vector<std::pair<PeerId, std::vector<float>>>& attribution,
    std::size_t vertex_count) {
  std::vector<float> rgb(vertex_count * 3, 0.82f);
  for (std::size_t v = 0; v < vertex_count; ++v) {
    float total = 0, peak = 0;
    for (const auto& [peer, amounts] : attribution) {
      total += amounts[v];
      peak = std::max(peak, amounts[v]);
    }
    if (!(total > 0)) continue;
    float mix[3] = {0, 0, 0};
    for (std::size_t k = 0; k < attribution.size(); ++k) {
      const float share = attribution[k].second[v] / peak;  // both at full: additive mix
      const std::array<float, 3> hue = peer_colour(k);
      for (int j = 0; j < 3; ++j) mix[j] += share * hue[j];
    }
    for (int j = 0; j < 3; ++j) rgb[3 * v + j] = std::min(1.f, mix[j]);
  }
  return rgb;
}

}  // namespace csculpt::peer
