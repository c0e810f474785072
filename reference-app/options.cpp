#include "options.h"

#include <charconv>
#include <cstdlib>
#include <cstring>

namespace {

constexpr const char* kUsage =
    "usage: csculpt-app [MESH] [--host | --join INVITE] [--name NAME] [--bind ENDPOINT]\n"
    "                   [--replay FILE] [--save PATH]\n"
    "                   [--screenshot PATH] [--exit-after SECONDS] [--bench-frames N]\n"
    "                   [--bench-warmup S] [--sphere-faces N] [--size WxH]\n"
    "  MESH            a .ply/.obj/.off/.stl file; without it, a built-in sphere\n"
    "  --host          host a session; prints `INVITE <invite>` on stdout\n"
    "  --join INVITE   join the session of INVITE\n"
    "  --name NAME     your name in the session's peer list (default $USER)\n"
    "  --bind ENDPOINT where the other peers reach you, e.g. tcp://192.168.1.5:7000 (port *\n"
    "                  picks a free one); default tcp://*:* (every interface), or with the\n"
    "                  panel's \"other machines\" unticked tcp://127.0.0.1:*\n"
    "  --replay FILE   feed recorded input events (see reference-app/README.md)\n"
    "  --save PATH     write the mesh (PLY: every channel) on exit\n"
    "  --screenshot P  write a PNG of the window on exit\n"
    "  --exit-after S  quit after S seconds (never before a --replay has ended)\n"
    "  --bench-frames N  print frame-time JSON lines (idle, sculpting) and quit\n"
    "  --bench-warmup S  run S seconds of untimed frames before the benchmark\n"
    "  --sphere-faces N  faces of the built-in sphere (default 160000)\n"
    "  --size WxH      window size (default 1280x800)\n";

// A name fits the panel's text field (and the library's 256-byte limit).
constexpr size_t kMaxName = 63;

template <typename T>
bool parse_number(const char* text, T& out) {
  const char* end = text + std::strlen(text);
  auto [ptr, ec] = std::from_chars(text, end, out);
  return ec == std::errc() && ptr == end;
}

}  // namespace

ParseResult parse_options(int argc, char** argv) {
  AppOptions options;
  auto fail = [](std::string why) { return ParseResult{std::nullopt, why + "\n" + kUsage, 2}; };
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&](const char*& out) {
      if (i + 1 >= argc) return false;
      out = argv[++i];
      return true;
    };
    const char* v = nullptr;
    if (arg == "-h" || arg == "--help") return {std::nullopt, kUsage, 0};
    if (arg == "--host") {
      options.host = true;
    } else if (arg == "--join") {
      if (!value(v)) return fail("--join needs an invite");
      options.join_invite = v;
    } else if (arg == "--name") {
      if (!value(v) || !*v || std::strlen(v) > kMaxName)
        return fail("--name needs a name of 1 to " + std::to_string(kMaxName) + " bytes");
      options.name = v;
    } else if (arg == "--bind") {
      if (!value(v) || std::strncmp(v, "tcp://", 6) != 0)
        return fail("--bind needs a tcp:// endpoint, e.g. tcp://*:7000");
      options.bind = v;
    } else if (arg == "--replay") {
      if (!value(v)) return fail("--replay needs a file");
      options.replay_path = v;
    } else if (arg == "--save") {
      if (!value(v)) return fail("--save needs a path");
      options.save_path = v;
    } else if (arg == "--screenshot") {
      if (!value(v)) return fail("--screenshot needs a path");
      options.screenshot_path = v;
    } else if (arg == "--exit-after") {
      double seconds = 0;
      if (!value(v) || !parse_number(v, seconds) || seconds < 0)
        return fail("--exit-after needs a number of seconds");
      options.exit_after_seconds = seconds;
    } else if (arg == "--bench-frames") {
      if (!value(v) || !parse_number(v, options.bench_frames) || options.bench_frames == 0)
        return fail("--bench-frames needs a positive count");
    } else if (arg == "--bench-warmup") {
      if (!value(v) || !parse_number(v, options.bench_warmup_seconds) ||
          options.bench_warmup_seconds < 0)
        return fail("--bench-warmup needs a number of seconds");
    } else if (arg == "--sphere-faces") {
      if (!value(v) || !parse_number(v, options.sphere_faces) || options.sphere_faces < 20)
        return fail("--sphere-faces needs a count of at least 20");
    } else if (arg == "--size") {
      if (!value(v)) return fail("--size needs WxH");
      const std::string size = v;
      const auto x = size.find('x');
      if (x == std::string::npos || !parse_number(size.substr(0, x).c_str(), options.width) ||
          !parse_number(size.substr(x + 1).c_str(), options.height) || options.width < 64 ||
          options.height < 64)
        return fail("--size needs WxH, each at least 64");
    } else if (!arg.empty() && arg[0] == '-') {
      return fail("unknown option " + arg);
    } else if (options.mesh_path.empty()) {
      options.mesh_path = arg;
    } else {
      return fail("only one mesh file can be opened");
    }
  }
  if (options.name.empty()) {
    const char* user = std::getenv("USER");
    options.name = user && *user && std::strlen(user) <= kMaxName ? user : "artist";
  }
  if (options.host && !options.join_invite.empty())
    return fail("--host and --join exclude each other");
  return {options, "", 0};
}
