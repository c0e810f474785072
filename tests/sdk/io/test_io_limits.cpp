// What the readers refuse before it costs memory (issue 12, finding 7): vertices no face uses
// beyond the stated share, devices and endless streams, header counts the file cannot hold.
// The memory figures of the refusals are measured on the command line (tests/cli).
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <array>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "csculpt/error.h"
#include "csculpt/io.h"
#include "test_support.h"

namespace csculpt {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

/// A binary PLY of `vertices` zero positions (a hole, so the file is sparse and written at
/// once) and the given triangles.
void write_sparse_ply(const std::string& path, std::uint64_t vertices,
                      const std::vector<std::array<std::int32_t, 3>>& faces) {
  {
    std::ofstream out(path, std::ios::binary);
    out << "ply\nformat binary_little_endian 1.0\nelement vertex " << vertices
        << "\nproperty float x\nproperty float y\nproperty float z\nelement face " << faces.size()
        << "\nproperty list uchar int vertex_indices\nend_header\n";
  }
  fs::resize_file(path, fs::file_size(path) + vertices * 12);
  std::ofstream out(path, std::ios::binary | std::ios::app);
  for (const auto& f : faces) {
    out.put(3);
    out.write(reinterpret_cast<const char*>(f.data()), 12);  // little-endian host
  }
}

std::string error_of(const std::string& path) {
  try {
    read_mesh(path);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "(read without an error)";
}

class IoLimits : public ::testing::Test {
 protected:
  std::string path(const std::string& name) const { return (scratch_.path() / name).string(); }
  test::TestDir scratch_{"csculpt_io_limits"};
};

TEST_F(IoLimits, MostlyUnusedVerticesBeyondAMillionAreRefusedNamingTheCounts) {
  const std::string p = path("sparse.ply");
  write_sparse_ply(p, 1'500'000, {{0, 1, 2}});
  const std::string e = error_of(p);
  EXPECT_EQ(e.rfind(p + ": ", 0), 0u) << e;
  EXPECT_NE(e.find("1499997 of 1500000 vertices"), std::string::npos) << e;
  EXPECT_THROW(read_mesh(p), InvalidInput);
}

TEST_F(IoLimits, UnusedVerticesWithinTheShareAreRead) {
  // Far more than half unused, but under the absolute count: stray vertices of a small mesh.
  const std::string few = path("few_used.ply");
  write_sparse_ply(few, 200'000, {{0, 1, 2}});
  EXPECT_EQ(read_mesh(few).vertex_count(), 200'000u);
  // Over a million unused, but fewer than half of all vertices.
  std::vector<std::array<std::int32_t, 3>> faces;
  for (std::int32_t v = 0; v + 2 < 1'100'000; v += 3) faces.push_back({v, v + 1, v + 2});
  const std::string half = path("half_used.ply");
  write_sparse_ply(half, 2'150'000, faces);
  EXPECT_EQ(read_mesh(half).vertex_count(), 2'150'000u);
}

TEST_F(IoLimits, DevZeroFailsFastNamingIt) {
  const auto t0 = Clock::now();
  const std::string e = error_of("/dev/zero");
  const double s = std::chrono::duration<double>(Clock::now() - t0).count();
  EXPECT_EQ(e.rfind("/dev/zero: ", 0), 0u) << e;
  EXPECT_NE(e.find("device"), std::string::npos) << e;
  EXPECT_LT(s, 1.0);
  RecordProperty("dev_zero_ms", static_cast<int>(s * 1000));
}

TEST_F(IoLimits, AnEndlessPipeOfZerosFailsAfterItsFirstChunk) {
  const std::string fifo = path("zeros");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  // The reader stops early: the writer's next write fails with EPIPE instead of a signal.
  const auto old = std::signal(SIGPIPE, SIG_IGN);
  std::thread writer([&] {
    std::FILE* f = std::fopen(fifo.c_str(), "wb");
    if (!f) return;
    const std::string zeros(1 << 16, '\0');
    for (int i = 0; i < 64 * 16; ++i) {  // 64 MiB, far past the point of refusal
      if (std::fwrite(zeros.data(), 1, zeros.size(), f) != zeros.size()) break;
    }
    std::fclose(f);
  });
  const auto t0 = Clock::now();
  const std::string e = error_of(fifo);
  const double s = std::chrono::duration<double>(Clock::now() - t0).count();
  writer.join();
  std::signal(SIGPIPE, old);
  EXPECT_EQ(e.rfind(fifo + ": not a regular file", 0), 0u) << e;
  EXPECT_LT(s, 1.0);
}

TEST_F(IoLimits, HeaderCountsBeyondTheBytesAreRefusedBeforeAllocating) {
  for (const char* format : {"ascii", "binary_little_endian"}) {
    const std::string p = path(std::string("claims_") + format + ".ply");
    std::ofstream(p) << "ply\nformat " << format
                     << " 1.0\nelement vertex 50000000\nproperty float x\nproperty float y\n"
                        "property float z\nelement face 1\nproperty list uchar int "
                        "vertex_indices\nend_header\n0 0 0\n";
    const auto t0 = Clock::now();
    const std::string e = error_of(p);
    EXPECT_LT(std::chrono::duration<double>(Clock::now() - t0).count(), 0.5);
    EXPECT_EQ(e.rfind(p + ": ", 0), 0u) << e;
    EXPECT_NE(e.find("50000000"), std::string::npos) << e;
  }
}

}  // namespace
}  // namespace csculpt
