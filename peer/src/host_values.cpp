#include "host_values.h"

#include <cmath>
#include <sstream>

#include "csculpt/error.h"

namespace csculpt::peer {
namespace {

[[noreturn]] void refuse(std::string_view what, const std::string& message) {
  throw InvalidInput(std::string(what) + ": " + message);
}

void check_position(const Vec3f& p, std::uint32_t v, const MergeFrame& frame,
                    std::string_view what) {
  const double dx = double{p.x} - frame.center.x, dy = double{p.y} - frame.center.y,
               dz = double{p.z} - frame.center.z;
  const double reach = double{kMaxReach} * frame.scale;
  if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) &&
      dx * dx + dy * dy + dz * dz <= reach * reach)
    return;
  std::ostringstream m;
  m << "the position of vertex " << v << " (" << p.x << ", " << p.y << ", " << p.z << ") ";
  if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)))
    m << "is not finite";
  else
    m << "is " << std::sqrt(dx * dx + dy * dy + dz * dz) << " from the session's centre, beyond "
      << kMaxReach << " x its initial bounding-box diagonal (" << frame.scale << ")";
  refuse(what, m.str());
}

/// How far outside its range a channel value may lie and still be accepted: float rounding in a
/// host's own brush or in a rebase leaves values a hair beyond a bound (-4e-12 for a metallic of
/// 0 was seen), which are edits as meant, not bad values. Merges clamp them into the range.
double range_slack(const ChannelDesc& desc) {
  const double span = double{desc.max_value} - double{desc.min_value};
  return std::isfinite(span) ? kRangeSlack * span : 0.0;
}

void check_channel_value(float value, const ChannelDesc& desc, std::uint32_t v,
                         std::string_view what) {
  const double slack = range_slack(desc);
  if (std::isfinite(value) && value >= desc.min_value - slack && value <= desc.max_value + slack)
    return;
  std::ostringstream m;
  m << "the " << desc.name << " value of vertex " << v << " (" << value << ") ";
  if (!std::isfinite(value))
    m << "is not finite";
  else
    m << "is outside the channel's range [" << desc.min_value << ", " << desc.max_value << "]";
  refuse(what, m.str());
}

}  // namespace

void check_host_values(const Mesh& local, const Mesh& base, const MergeFrame& frame,
                       std::string_view what) {
  for (std::uint32_t v = 0; v < local.positions.size(); ++v) {
    const Vec3f &p = local.positions[v], &b = base.positions[v];
    if (p.x != b.x || p.y != b.y || p.z != b.z) check_position(p, v, frame, what);
  }
  for (std::size_t c = 0; c < local.channels.size(); ++c) {
    const std::vector<float>&values = local.channels[c].values, &was = base.channels[c].values;
    for (std::size_t i = 0; i < values.size(); ++i)
      if (values[i] != was[i])
        check_channel_value(values[i], local.channels[c].desc,
                            static_cast<std::uint32_t>(i / local.channels[c].desc.width), what);
  }
}

void check_diff_values(const Diff& diff, const Mesh& base, const MergeFrame& frame,
                       std::string_view what) {
  const AttributeDiff& p = diff.positions;
  for (std::size_t i = 0; i < p.indices.size(); ++i)
    check_position({p.values[3 * i], p.values[3 * i + 1], p.values[3 * i + 2]}, p.indices[i], frame,
                   what);
  for (std::size_t c = 0; c < diff.channels.size() && c < base.channels.size(); ++c) {
    const AttributeDiff& change = diff.channels[c].change;
    const std::uint32_t w = base.channels[c].desc.width;
    for (std::size_t i = 0; i < change.values.size(); ++i)
      check_channel_value(change.values[i], base.channels[c].desc, change.indices[i / w], what);
  }
}

}  // namespace csculpt::peer
