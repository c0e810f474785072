// --bench-frames N: frame times with the app idle and while a stroke is drawn across the mesh
// (through the same input handlers as a person), one JSON line each, then quit.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <numeric>
#include <vector>

#include "app.h"

namespace {

double percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const size_t index =
      std::min(values.size() - 1, static_cast<size_t>(std::ceil(p * double(values.size())) - 1));
  return values[index];
}

}  // namespace

double App::thread_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

void App::print_dabs(const char* mode) {
  std::printf(
      "{\"bench\":\"app_dab\",\"mode\":\"%s\",\"faces\":%u,\"vertices\":%u,"
      "\"radius_px\":%.0f,\"dabs\":%zu,\"dab_ms_p50\":%.4f,\"dab_ms_p99\":%.4f,"
      "\"vertices_last_dab\":%u}\n",
      mode, document_.triangle_count(), document_.vertex_count(), double(brush_.radius_pixels),
      dab_ms_.size(), percentile(dab_ms_, 0.5), percentile(dab_ms_, 0.99),
      sculptor_.last_dab_vertices());
  std::fflush(stdout);
}

int App::run_bench() {
  int width = 0, height = 0;
  glfwGetFramebufferSize(window_, &width, &height);
  const uint32_t frames = options_.bench_frames;
  std::vector<double> frame_ms;
  frame_ms.reserve(frames);
  dab_ms_.reserve(size_t{frames} * 16);
  session_ms_.reserve(frames);
  session_cpu_ms_.reserve(frames);
  upload_ms_.reserve(frames);
  // In a session (--host / --join) the merged versions applied during the phase are counted:
  // the frames then include csc_session_update's rebase of the artist's arrays.
  uint64_t versions_before = session_.stats().versions_applied;
  auto print = [&](const char* mode) {
    const double p50 = percentile(frame_ms, 0.5), p99 = percentile(frame_ms, 0.99),
                 worst = percentile(frame_ms, 1.0);
    const csc_session_stats& stats = session_.stats();
    std::printf(
        "{\"bench\":\"app_frames\",\"mode\":\"%s\",\"faces\":%u,\"vertices\":%u,\"width\":%d,"
        "\"height\":%d,\"frames\":%u,\"frame_ms_p50\":%.3f,\"frame_ms_p99\":%.3f,\"frame_ms_max\":%"
        ".3f,"
        "\"fps_p50\":%.2f,\"fps_p99\":%.2f,\"drawn_faces\":%u,\"session_members\":%u,"
        "\"versions_applied\":%llu,\"session_ms_p99\":%.3f,\"session_ms_max\":%.3f,"
        "\"session_cpu_ms_p99\":%.3f,\"session_cpu_ms_max\":%.3f,\"session_cpu_ms_total\":%.1f,"
        "\"upload_ms_p99\":%.3f,\"upload_ms_max\":%.3f}\n",
        mode, document_.triangle_count(), document_.vertex_count(), width, height, frames, p50, p99,
        worst, 1000.0 / p50, 1000.0 / p99, renderer_.drawn_triangles_last(),
        session_.active() ? stats.members : 0u,
        static_cast<unsigned long long>(stats.versions_applied - versions_before),
        percentile(session_ms_, 0.99), percentile(session_ms_, 1.0),
        percentile(session_cpu_ms_, 0.99), percentile(session_cpu_ms_, 1.0),
        std::accumulate(session_cpu_ms_.begin(), session_cpu_ms_.end(), 0.0),
        percentile(upload_ms_, 0.99), percentile(upload_ms_, 1.0));
    std::fflush(stdout);
    versions_before = stats.versions_applied;
    session_ms_.clear();
    session_cpu_ms_.clear();
    upload_ms_.clear();
  };
  auto timed_frame = [&] {
    const auto start = std::chrono::steady_clock::now();
    benchmarking_frames_ = true;
    frame();
    benchmarking_frames_ = false;
    glFinish();  // count the frame's drawing, not only its submission
    frame_ms.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
            .count());
  };
  const double warm_until = glfwGetTime() + options_.bench_warmup_seconds;
  for (int warm = 0; warm < 5 || glfwGetTime() < warm_until; ++warm) frame();
  versions_before = session_.stats().versions_applied;
  for (uint32_t i = 0; i < frames; ++i) timed_frame();
  print("idle");

  // A circle around the window's centre, sculpted with the draw brush, one step per frame.
  frame_ms.clear();
  benchmarking_ = true;
  const int window_w = window_width_, window_h = window_height_;
  const double cx = window_w / 2.0, cy = window_h / 2.0, r = std::min(window_w, window_h) * 0.2;
  on_cursor(cx + r, cy);
  on_button(GLFW_MOUSE_BUTTON_LEFT, GLFW_PRESS, 0);
  for (uint32_t i = 0; i < frames; ++i) {
    const double angle = 6.283185307179586 * double(i + 1) / double(frames);
    on_cursor(cx + r * std::cos(angle), cy + r * std::sin(angle));
    timed_frame();
  }
  on_button(GLFW_MOUSE_BUTTON_LEFT, GLFW_RELEASE, 0);
  print("sculpting");
  print_dabs("between_frames");
  // The same circle again with no frame drawn between the dabs: on this machine the renderer
  // (llvmpipe) runs on the CPU and leaves the caches cold for the next frame's dab; with a
  // GPU, a dab finds them closer to this. Undone first: the same surface under the same dabs.
  undo();
  dab_ms_.clear();
  on_cursor(cx + r, cy);
  on_button(GLFW_MOUSE_BUTTON_LEFT, GLFW_PRESS, 0);
  for (uint32_t i = 0; i < frames; ++i) {
    const double angle = 6.283185307179586 * double(i + 1) / double(frames);
    on_cursor(cx + r * std::cos(angle), cy + r * std::sin(angle));
  }
  on_button(GLFW_MOUSE_BUTTON_LEFT, GLFW_RELEASE, 0);
  print_dabs("back_to_back");
  benchmarking_ = false;
  return 0;
}
