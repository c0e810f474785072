// `csculpt bench wire`: size and speed of the diff wire format (sdk/schema/diff.fbs) for one
// stroke that touches a given number of vertices, per stroke kind; the paper sends ~170 KB per
// stroke, the target is <= 60 KB for 10,000 vertices at <= 1e-5 of the diagonal.
#include "bench_wire.h"

#include "bench_stats.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

#include "csculpt/diff.h"
#include "csculpt/hierarchy.h"
#include "csculpt/testkit/generate.h"
#include "csculpt/wire.h"

namespace csculpt::cli {
namespace {

using Clock = BenchClock;

struct Case {
  const char* name;
  Stroke stroke;
  double tolerance_scale;  // 0 = lossless
};

}  // namespace

int bench_wire(const BenchWireOptions& o) {
  Mesh base = make_sphere(o.faces, /*materials=*/true);
  const Topology topology =
      Topology::build(static_cast<std::uint32_t>(base.vertex_count()), base.triangles);
  const double diagonal = bbox_diagonal(base.positions);
  // A cap of chord radius r on the unit sphere holds about r^2/4 of its vertices.
  const double fraction = std::min(1.0, double(o.touched) / double(base.vertex_count()));
  const float radius = static_cast<float>(2.0 * std::sqrt(fraction));
  const Vec3f center{0.36f, 0.48f, 0.8f};

  std::vector<Case> cases;
  auto stroke = [&](Stroke::Kind kind, float strength) {
    Stroke s;
    s.kind = kind;
    s.center = center;
    s.radius = radius;
    s.strength = strength;
    s.axis = {0.6f, 0.8f, 0.f};
    return s;
  };
  cases.push_back({"grab", stroke(Stroke::Kind::grab, 0.2f), 1});
  cases.push_back({"inflate", stroke(Stroke::Kind::inflate, 0.1f), 1});
  cases.push_back({"detail", stroke(Stroke::Kind::detail, 0.02f), 1});
  cases.push_back({"twist", stroke(Stroke::Kind::twist, 0.5f), 1});
  cases.push_back({"smooth", stroke(Stroke::Kind::smooth, 0.5f), 1});
  cases.push_back({"paint", stroke(Stroke::Kind::paint, 1.f), 1});
  cases.push_back({"grab-lossless", stroke(Stroke::Kind::grab, 0.2f), 0});

  for (const Case& c : cases) {
    Mesh edited = base;
    apply_stroke(edited, c.stroke, &topology);
    const Diff diff = capture_diff(base, edited);
    EncodeOptions eo;
    eo.position_tolerance = o.tolerance * c.tolerance_scale;
    eo.channel_tolerance = c.tolerance_scale > 0 ? eo.channel_tolerance : 0;
    eo.position_scale = diagonal;
    DiffHeader header;
    header.author = "bench";
    std::vector<double> encode_ms, decode_ms;
    std::vector<std::uint8_t> bytes;
    Diff decoded;
    for (std::uint32_t r = 0; r < o.repeat + 1; ++r) {
      const auto t0 = Clock::now();
      bytes = encode_diff(diff, base, header, eo);
      const auto t1 = Clock::now();
      decoded = decode_diff(bytes, base);
      const auto t2 = Clock::now();
      if (r == 0) continue;
      encode_ms.push_back(ms_between(t0, t1));
      decode_ms.push_back(ms_between(t1, t2));
    }
    // Largest position error of the decoded diff against the edit, relative to the diagonal.
    Mesh received = base;
    apply_diff(decoded, received);
    double max_err = 0;
    for (std::size_t v = 0; v < base.vertex_count(); ++v) {
      const Vec3f& a = edited.positions[v];
      const Vec3f& b = received.positions[v];
      max_err = std::max({max_err, std::abs(double(a.x) - b.x), std::abs(double(a.y) - b.y),
                          std::abs(double(a.z) - b.z)});
    }
    double max_channel_err = 0;
    for (std::size_t k = 0; k < base.channels.size(); ++k)
      for (std::size_t i = 0; i < base.channels[k].values.size(); ++i)
        max_channel_err = std::max(max_channel_err, std::abs(double(edited.channels[k].values[i]) -
                                                             received.channels[k].values[i]));
    const std::size_t touched = diff.touched_vertices();
    std::printf(
        "{\"bench\":\"wire\",\"stroke\":\"%s\",\"faces\":%zu,\"vertices\":%zu,"
        "\"touched_vertices\":%zu,\"bytes\":%zu,\"bytes_per_touched_vertex\":%.3f,"
        "\"raw_bytes\":%zu,\"position_tolerance\":%g,\"max_position_error\":%.3g,"
        "\"max_channel_error\":%.3g,\"encode_ms\":%.3f,\"decode_ms\":%.3f,\"repeat\":%u}\n",
        c.name, base.face_count(), base.vertex_count(), touched, bytes.size(),
        touched ? double(bytes.size()) / double(touched) : 0.0,
        std::size_t(diff.positions.size() * 16 +
                    [&] {
                      std::size_t s = 0;
                      for (const auto& ch : diff.channels)
                        s += ch.change.size() * (4 + 4 * ch.desc.width);
                      return s;
                    }()),
        eo.position_tolerance, max_err / diagonal, max_channel_err, median(encode_ms),
        median(decode_ms), o.repeat);
  }
  return 0;
}

}  // namespace csculpt::cli
