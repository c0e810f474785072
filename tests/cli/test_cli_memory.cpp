// `csculpt` under memory pressure (issue 12, finding 7), each run a child process whose peak
// RSS wait4 reports: a sparse PLY of mostly unused vertices is refused before a hierarchy is
// built on it, and running out of address space (prlimit --as) gives the one-line error
// contract naming the file, never a bare std::bad_alloc.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "csculpt/io.h"
#include "csculpt/testkit/generate.h"
#include "test_support.h"

namespace csculpt {
namespace {

namespace fs = std::filesystem;

struct Outcome {
  int code = -1;
  std::string err;
  long peak_rss_kb = 0;
};

/// Runs `argv` with stdout to /dev/null and stderr captured; the peak RSS is the child's own.
Outcome run(const std::vector<std::string>& argv, const fs::path& err_file) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    std::freopen("/dev/null", "w", stdout);
    std::freopen(err_file.c_str(), "w", stderr);
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    ::execvp(args[0], args.data());
    ::_exit(127);
  }
  Outcome r;
  int status = 0;
  rusage usage{};
  if (pid > 0 && ::wait4(pid, &status, 0, &usage) == pid) {
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.peak_rss_kb = usage.ru_maxrss;
  }
  std::ifstream in(err_file);
  std::ostringstream text;
  text << in.rdbuf();
  r.err = text.str();
  return r;
}

bool has_prlimit() {
  return std::system("prlimit --version >/dev/null 2>&1") == 0;
}

class CliMemory : public ::testing::Test {
 protected:
  fs::path dir() const { return scratch_.path(); }
  test::TestDir scratch_{"csculpt_cli_memory"};
};

TEST_F(CliMemory, SparsePlyOfUnusedVerticesIsRefusedBeforeTheHierarchy) {
  // 3M zero vertices (a hole: 36 MB that take no disk) and one triangle.
  const std::string p = (dir() / "sparse.ply").string();
  {
    std::ofstream out(p, std::ios::binary);
    out << "ply\nformat binary_little_endian 1.0\nelement vertex 3000000\nproperty float x\n"
           "property float y\nproperty float z\nelement face 1\n"
           "property list uchar int vertex_indices\nend_header\n";
  }
  fs::resize_file(p, fs::file_size(p) + 3'000'000ull * 12);
  {
    std::ofstream out(p, std::ios::binary | std::ios::app);
    const std::int32_t face[3] = {0, 1, 2};
    out.put(3);
    out.write(reinterpret_cast<const char*>(face), sizeof face);
  }
  const auto file_kb = static_cast<long>(fs::file_size(p) / 1024);
  const Outcome r = run({CSCULPT_CLI, "hierarchy", p}, dir() / "err");
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_EQ(r.err, "csculpt: error: " + p +
                       ": 2999997 of 3000000 vertices are used by no face (at most half, or "
                       "1000000, may be unused)\n");
  // The file in memory and its positions, each once, and the program: not a hierarchy.
  EXPECT_LT(r.peak_rss_kb, 3 * file_kb + 64 * 1024) << "file " << file_kb << " KB";
  RecordProperty("file_kb", static_cast<int>(file_kb));
  RecordProperty("peak_rss_kb", static_cast<int>(r.peak_rss_kb));
  std::printf("[figure] sparse PLY of %ld KB refused at a peak RSS of %ld KB\n", file_kb,
              r.peak_rss_kb);
}

TEST_F(CliMemory, OutOfAddressSpaceIsOneErrorLineNamingTheFile) {
  if (!has_prlimit()) GTEST_SKIP() << "needs prlimit (util-linux)";
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
  // A sanitizer's shadow memory needs terabytes of address space: under a limit the CLI
  // cannot even start. The release phase of ./dev test runs this.
  GTEST_SKIP() << "address-space limits and sanitizers do not mix";
#endif
  const std::string p = (dir() / "large.ply").string();
  write_mesh(make_sphere(500'000), p);
  // From too little to read the file up to enough to build the hierarchy: every run either
  // succeeds or prints the contract's one line; some must have run out of memory.
  int out_of_memory = 0;
  for (int mb = 20; mb <= 120; mb += 10) {
    const Outcome r =
        run({"prlimit", "--as=" + std::to_string(mb << 20), CSCULPT_CLI, "hierarchy", p},
            dir() / "err");
    if (r.code == 0) continue;
    EXPECT_EQ(r.code, 1) << mb << " MB: " << r.err;
    EXPECT_EQ(r.err.rfind("csculpt: error: " + p + ": ", 0), 0u) << mb << " MB: " << r.err;
    EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << mb << " MB: " << r.err;
    if (r.err.find("out of memory") != std::string::npos) ++out_of_memory;
  }
  EXPECT_GT(out_of_memory, 0);
}

}  // namespace
}  // namespace csculpt
