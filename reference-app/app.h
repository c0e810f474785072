// The app: a GLFW window with the mesh document, the brushes, the panels and a session.
// app.cpp: start-up, the main loop, rendering and the session's per-frame work;
// app_input.cpp: mouse and keys (strokes, camera, shortcuts); panels.cpp: the ImGui panels;
// cursors.cpp: presence (this artist's cursor out, the others' drawn); bench.cpp: --bench-frames.
#pragma once

#include <GLFW/glfw3.h>
#include <glm/vec3.hpp>

#include <array>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "brush.h"
#include "bvh.h"
#include "camera.h"
#include "draw_schedule.h"
#include "host_staging.h"
#include "input.h"
#include "mesh_document.h"
#include "mesh_preparation.h"
#include "options.h"
#include "renderer.h"
#include "replay.h"
#include "sculptor.h"
#include "session_link.h"
#include "stroke_history.h"
#include "tablet_pressure.h"

int run_app(const AppOptions& options);

class App final : public InputHandlers {
 public:
  explicit App(const AppOptions& options) : options_(options) {}
  App(const App&) = delete;
  App& operator=(const App&) = delete;
  ~App() override;
  int run();

  // InputHandlers (app_input.cpp): GLFW's callbacks and the replay call these.
  void on_cursor(double x, double y) override;
  void on_button(int button, int action, int mods) override;
  void on_key(int key, int action, int mods) override;
  void on_scroll(double dy) override;
  void on_pressure(float pressure) override { pressure_ = pressure; }
  bool in_session() const override { return session_.active(); }
  /** Something on screen changed: the next frames are drawn (draw_schedule.h). */
  void redraw() { schedule_.request(); }
  void on_window_size(int width, int height) {
    window_width_ = width, window_height_ = height;
    redraw();
  }
  unsigned long long session_version() const override {
    return session_.active() ? session_.version() : 0;
  }

 private:
  enum class Drag { none, stroke, orbit, pan };
  struct Rect {
    float x, y, w, h;
  };

  // app.cpp
  bool open_window();
  void open_start_mesh();
  void layout_changed();
  void arrays_changed(DrawClusters clusters, MeshBuffers buffers = {});
  std::function<void(PreparedMesh&)> buffer_filler() const;
  void finish_join();
  bool frame();
  bool busy() const;
  bool should_quit() const;
  void render(bool with_ui);
  void session_tick();
  void take_session_changes();
  void host_session();
  /** While a hosted session is being created: prints its invite, or reports why it failed. */
  void poll_host();
  void join_session(const std::string& invite);
  PeerSettings peer_settings() const;  // the panel's name and reach, else the command line's
  void report(const std::string& message);
  void toggle_attribution_view();
  void finish();
  // app_input.cpp
  bool over_panel(double x, double y) const;
  bool pick(double x, double y, RayHit& hit) const;
  DabInput dab_input(const RayHit& hit) const;
  void begin_stroke(int mods);
  void continue_stroke();
  void end_stroke();
  void undo();
  void session_step(bool redo);
  void redo();
  bool shortcut(int key, int mods);
  // panels.cpp
  void draw_panels();
  void draw_tool_panel();
  void draw_session_panel();
  void draw_brush_cursor();
  // cursors.cpp
  void send_presence();
  bool surface_normal(glm::vec3 point, float radius, glm::vec3& normal) const;
  void draw_remote_cursors();
  // bench.cpp
  int run_bench();
  static double thread_cpu_ms();  // the calling thread's CPU time
  /** One JSON line of the dab times measured since they were last cleared. */
  void print_dabs(const char* mode);

  AppOptions options_;
  GLFWwindow* window_ = nullptr;
  GLFWwindow* upload_window_ = nullptr;  // hidden, sharing window_'s GL objects (a join's buffers)
  // The window's size in screen coordinates, kept by its callback: asking X11 for it
  // (glfwGetWindowSize) is a round trip to the server, twice per brush dab otherwise.
  int window_width_ = 0, window_height_ = 0;
  bool imgui_ready_ = false;
  MeshDocument document_;
  TriangleBvh bvh_;
  StrokeHistory history_;
  Sculptor sculptor_{document_, bvh_, history_};
  Renderer renderer_;
  OrbitCamera camera_;
  BrushSettings brush_;
  ViewSettings view_;
  ReplayPlayer replay_;
  SessionLink session_;
  HostStaging host_staging_;  // memory for hosting's copies of the arrays and the BVH
  std::unique_ptr<MeshPreparation> preparing_;  // a joined mesh being made ready
  double join_ms_ = 0;  // what taking the joined mesh cost the UI thread (SESSION line)
  double host_ms_ = 0;  // what starting to host cost the UI thread (SESSION line)
  TabletPressure tablet_;
  std::string tablet_status_;  // shown beside the pressure settings

  // Input state. The press uses the position of the last cursor event, never a live
  // glfwGetCursorPos (which races with a fast xdotool drag: see the Debian notes).
  double cursor_x_ = 0, cursor_y_ = 0;
  double drag_x_ = 0, drag_y_ = 0;  // the last position the drag consumed
  float pressure_ = 1.f;
  Drag drag_ = Drag::none;
  BrushKind stroke_kind_ = BrushKind::draw;
  bool stroke_invert_ = false;
  glm::vec3 grab_anchor_{0.f};

  // Panels.
  std::vector<Rect> panel_rects_;  // last frame's panels: clicks there are not strokes
  bool show_ui_ = true;
  bool attribution_view_ = false, attribution_dirty_ = false;
  std::string error_;
  std::array<char, 4096> join_text_{};
  std::array<char, 64> name_text_{};  // the panel's name field; empty: --name's
  bool reachable_ = true;  // listen on every interface, not only this machine's (no --bind)
  std::array<char, 1024> path_text_{};
  std::string shown_message_;

  std::vector<uint32_t> undo_changed_;

  // Drawing on demand: what the last drawn frame showed of the session, and frames drawn.
  DrawSchedule schedule_;
  uint64_t shown_session_look_ = 0;
  unsigned long long frames_drawn_ = 0;
  double last_draw_ms_ = 0;  // render and swap of the last frame drawn, for the panel

  // Timing.
  double start_time_ = 0;
  bool ready_printed_ = false;
  std::vector<double> dab_ms_;  // filled while benchmarking
  bool benchmarking_ = false;
  // Per timed frame: the session's calls with applying what they brought, and the upload.
  std::vector<double> session_ms_, upload_ms_;
  // The UI thread's CPU time in the session's part of each frame: its own work, which a
  // loaded machine's preemptions do not inflate (session_ms_ is wall time).
  std::vector<double> session_cpu_ms_;
  bool benchmarking_frames_ = false;
};
