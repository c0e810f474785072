// The command line of csculpt-app (the scripting contract of issue 11).
#pragma once

#include <cstdint>
#include <optional>
#include <string>

struct AppOptions {
  std::string mesh_path;  // empty: the built-in sphere
  bool host = false;
  std::string join_invite;  // empty: no join
  std::string name;         // shown to the other artists; default $USER, else "artist"
  std::string bind;         // the session endpoint to listen on; empty: the panel's choice
  std::string replay_path;
  std::string save_path;
  std::string screenshot_path;
  std::optional<double> exit_after_seconds;
  uint32_t bench_frames = 0;        // 0: no benchmark
  double bench_warmup_seconds = 0;  // untimed frames first (e.g. while peers join)
  uint32_t sphere_faces = 160000;
  int width = 1280;
  int height = 800;
};

struct ParseResult {
  std::optional<AppOptions> options;  // empty: print `message` and exit with `exit_code`
  std::string message;
  int exit_code = 0;
};

ParseResult parse_options(int argc, char** argv);
