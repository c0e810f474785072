#include "app.h"

#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <epoxy/gl.h>
#include <imgui.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <thread>

#include "screenshot.h"

namespace {

App* app_of(GLFWwindow* window) {
  return static_cast<App*>(glfwGetWindowUserPointer(window));
}

// GLFW callbacks: ImGui sees every event first (its 1.86 backend is not installed with
// callbacks of its own), then the app decides. Every event asks for frames to be drawn.
void cursor_callback(GLFWwindow* window, double x, double y) {
  app_of(window)->redraw();
  app_of(window)->on_cursor(x, y);
}
void button_callback(GLFWwindow* window, int button, int action, int mods) {
  app_of(window)->redraw();
  ImGui_ImplGlfw_MouseButtonCallback(window, button, action, mods);
  app_of(window)->on_button(button, action, mods);
}
void key_callback(GLFWwindow* window, int key, int scancode, int action, int mods) {
  app_of(window)->redraw();
  ImGui_ImplGlfw_KeyCallback(window, key, scancode, action, mods);
  app_of(window)->on_key(key, action, mods);
}
void char_callback(GLFWwindow* window, unsigned int c) {
  app_of(window)->redraw();
  ImGui_ImplGlfw_CharCallback(window, c);
}
void scroll_callback(GLFWwindow* window, double dx, double dy) {
  app_of(window)->redraw();
  ImGui_ImplGlfw_ScrollCallback(window, dx, dy);
  app_of(window)->on_scroll(dy);
}
// Exposed, resized, focused, entered or left: the picture must be drawn again.
void refresh_callback(GLFWwindow* window) {
  app_of(window)->redraw();
}
void size_callback(GLFWwindow* window, int, int) {
  app_of(window)->redraw();
}
void window_size_callback(GLFWwindow* window, int width, int height) {
  app_of(window)->on_window_size(width, height);
}
void focus_callback(GLFWwindow* window, int) {
  app_of(window)->redraw();
}
void enter_callback(GLFWwindow* window, int) {
  app_of(window)->redraw();
}
void error_callback(int code, const char* description) {
  std::fprintf(stderr, "csculpt-app: GLFW error %d: %s\n", code, description);
}

}  // namespace

int run_app(const AppOptions& options) {
  if (csc_version() / 10000 != CSC_VERSION_MAJOR || csc_version() < CSC_VERSION_NUMBER) {
    std::fprintf(stderr, "csculpt-app: built for libcsculpt %s, loaded %s\n", CSC_VERSION_STRING,
                 csc_version_string());
    return 1;
  }
  App app(options);
  return app.run();
}

App::~App() {
  preparing_.reset();  // its thread may be filling buffers in the upload window's context
  if (imgui_ready_) {
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
  }
  if (window_) {
    renderer_.release();  // its GL objects need the context: free them while it exists
    if (upload_window_) glfwDestroyWindow(upload_window_);
    glfwDestroyWindow(window_);
  }
  glfwTerminate();
}

bool App::open_window() {
  glfwSetErrorCallback(error_callback);
  if (!glfwInit()) return false;
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  window_ = glfwCreateWindow(options_.width, options_.height, "cSculpt", nullptr, nullptr);
  if (!window_) return false;
  // Hidden, its context sharing the window's objects: a joined mesh's buffers are filled in
  // it on the preparation's thread (mesh_preparation.h). Without it they are filled here.
  glfwWindowHint(GLFW_VISIBLE, GLFW_FALSE);
  upload_window_ = glfwCreateWindow(1, 1, "cSculpt uploads", nullptr, window_);
  glfwWindowHint(GLFW_VISIBLE, GLFW_TRUE);
  glfwMakeContextCurrent(window_);
  glfwSwapInterval(options_.bench_frames > 0 ? 0 : 1);
  glfwSetWindowUserPointer(window_, this);

  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGuiIO& io = ImGui::GetIO();
  io.IniFilename = nullptr;  // the same layout on every run (tests compare pictures)
  ImGui::StyleColorsDark();
  ImGui_ImplGlfw_InitForOpenGL(window_, false);
  ImGui_ImplOpenGL3_Init("#version 330 core");
  imgui_ready_ = true;
  glfwSetCursorPosCallback(window_, cursor_callback);
  glfwSetMouseButtonCallback(window_, button_callback);
  glfwSetKeyCallback(window_, key_callback);
  glfwSetCharCallback(window_, char_callback);
  glfwSetScrollCallback(window_, scroll_callback);
  glfwSetWindowRefreshCallback(window_, refresh_callback);
  glfwSetFramebufferSizeCallback(window_, size_callback);
  glfwSetWindowSizeCallback(window_, window_size_callback);
  glfwGetWindowSize(window_, &window_width_, &window_height_);
  glfwSetWindowFocusCallback(window_, focus_callback);
  glfwSetCursorEnterCallback(window_, enter_callback);
  if (!tablet_.open(window_, tablet_status_))
    tablet_status_ = "no pen: " + tablet_status_;
  else
    tablet_status_ = std::to_string(tablet_.tablets()) + " pen device(s)";
  return true;
}

void App::report(const std::string& message) {
  error_ = error_.empty() ? message : error_ + "\n" + message;  // keep earlier messages in view
  std::fprintf(stderr, "csculpt-app: %s\n", message.c_str());
  schedule_.request();
}

void App::open_start_mesh() {
  std::string error;
  if (!options_.mesh_path.empty() && document_.load(options_.mesh_path, error)) return;
  document_.make_sphere(options_.sphere_faces);
  if (!error.empty()) report(error + " (showing the built-in sphere)");
}

// The joined session's mesh, prepared off this thread (mesh_preparation.h), replaces the
// document; the session becomes active. What is left here is the upload.
void App::finish_join() {
  std::string error;
  const auto start = std::chrono::steady_clock::now();
  PreparedMesh prepared;
  const bool ok = preparing_->take(prepared, error);
  preparing_.reset();
  if (!ok) {
    report(error);
    session_.leave();
    return;
  }
  document_ = std::move(prepared.document);
  bvh_ = std::move(prepared.bvh);
  arrays_changed(std::move(prepared.clusters), prepared.buffers);
  session_.hand_bvh(std::move(prepared.worker_bvh), std::move(prepared.worker_positions));
  session_.adopted();
  join_ms_ =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

// Fills a joined mesh's GL buffers on the preparation's thread, in the upload window's context.
std::function<void(PreparedMesh&)> App::buffer_filler() const {
  if (!upload_window_) return {};
  return [window = upload_window_](PreparedMesh& prepared) {
    glfwMakeContextCurrent(window);
    prepared.buffers = Renderer::fill_buffers(prepared.document, prepared.clusters);
    glfwMakeContextCurrent(nullptr);
  };
}

// After the document got new arrays (open, the built-in sphere): everything derived from
// them is rebuilt.
void App::layout_changed() {
  bvh_.build(document_.positions, document_.triangles);
  DrawClusters clusters;
  clusters.build(document_.positions, document_.triangles);
  arrays_changed(std::move(clusters));
}

// What derives from the document's arrays but the BVH: strokes, undo, the GPU's copy (drawn
// in `clusters`, built for these arrays; in `buffers` if they were filled already), the
// camera's framing.
void App::arrays_changed(DrawClusters clusters, MeshBuffers buffers) {
  sculptor_.reset();
  history_.reset(document_);
  if (buffers.index)
    renderer_.adopt_mesh(document_, std::move(clusters), buffers);
  else
    renderer_.upload_mesh(document_, std::move(clusters));
  // Frame the mesh: its bounding box's centre and half diagonal.
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  for (size_t i = 0; i < document_.positions.size(); i += 3)
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::fmin(lo[a], document_.positions[i + a]);
      hi[a] = std::fmax(hi[a], document_.positions[i + a]);
    }
  const glm::vec3 extent = hi - lo;
  camera_.frame((lo + hi) * 0.5f,
                0.5f * std::sqrt(extent.x * extent.x + extent.y * extent.y + extent.z * extent.z));
  std::snprintf(path_text_.data(), path_text_.size(), "%s", "");
  attribution_dirty_ = true;
  schedule_.request();
}

// The session is created on the worker; session_tick() prints the invite once it exists.
void App::host_session() {
  const auto start = std::chrono::steady_clock::now();
  HostCopy copy = host_staging_.copy(document_, bvh_);
  session_.host(std::move(copy.content), std::move(copy.bvh), peer_settings());
  host_ms_ =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

void App::poll_host() {
  std::string error;
  const int hosted = session_.poll_host(error);
  if (hosted < 0) report(error);  // the artist's own undo history is still there
  if (hosted > 0) {
    // Undo of solo strokes would fight the session's versions. The artist may be mid-stroke:
    // that stroke stays open, and is handed to the session when it ends.
    history_.forget_strokes();
    std::printf("INVITE %s\n", session_.invite());
    std::fflush(stdout);
  }
}

void App::join_session(const std::string& invite) {
  if (drag_ == Drag::stroke) end_stroke();
  session_.begin_join(invite, peer_settings());
}

// Every interface by default: the artists this app is for sit at other machines, and every
// peer is connected to by every other, so a joiner's endpoint must be reachable as well as the
// host's. The invite carries this machine's address there, not 0.0.0.0.
PeerSettings App::peer_settings() const {
  const std::string typed = name_text_.data();
  std::string bind = options_.bind;
  if (bind.empty()) bind = reachable_ ? "tcp://*:*" : "tcp://127.0.0.1:*";
  return {typed.empty() ? options_.name : typed, bind};
}

// The session's attribution colours (who edited where) drawn in place of the albedo.
void App::toggle_attribution_view() {
  attribution_view_ = !attribution_view_;
  attribution_dirty_ = true;
  if (!attribution_view_) renderer_.upload_values(document_);
}

// What the session changed (merged versions, the artist's undo, the wire's rounding of the
// strokes) into the document: only between strokes, and only once the worker's mirror holds
// every stroke handed to it, so the artist's own work is never overwritten by an older state.
void App::take_session_changes() {
  const std::shared_ptr<const MeshChanges> changes = session_.take_changes();
  if (!changes || changes->vertices.empty()) return;
  const uint32_t stride = document_.values_per_vertex();
  for (size_t i = 0; i < changes->vertices.size(); ++i)
    document_.set_vertex_values(changes->vertices[i], &changes->values[i * stride]);
  sculptor_.adopt_version(changes->vertices, changes->normals, changes->bvh_nodes,
                          changes->bvh_boxes);
  attribution_dirty_ = true;
}

void App::session_tick() {
  if (!session_.active() && !session_.joining() && !host_staging_.prepared_for(document_))
    host_staging_.prepare(document_, bvh_);  // for the next click on Host (host_staging.h)
  if (session_.starting_host()) poll_host();
  if (session_.joining()) {
    std::string error;
    const int joined = session_.poll_join(error);
    if (joined < 0) report(error);
    if (joined > 0) {
      preparing_.reset();  // one preparation at a time: the upload context is current on one thread
      preparing_ = std::make_unique<MeshPreparation>(session_.take_joined_mesh(), buffer_filler());
    }
  }
  if (preparing_ && preparing_->ready()) finish_join();
  if (!session_.active()) return;
  session_.poll_events();
  // What the session shows changed (a version, a peer, a cursor, a message): draw it once;
  // the running figures (bytes, latency) are redrawn a few times a second.
  const uint64_t look = session_.look();
  if (look != shown_session_look_ || (show_ui_ && schedule_.figures_due(glfwGetTime())))
    schedule_.request(1);
  shown_session_look_ = look;
  send_presence();
  if (drag_ != Drag::stroke) take_session_changes();  // never inside a stroke
}

void App::render(bool with_ui) {
  int width = 0, height = 0;
  glfwGetFramebufferSize(window_, &width, &height);
  glViewport(0, 0, width, height);
  glClearColor(0.16f, 0.17f, 0.19f, 1.f);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  if (width > 0 && height > 0)
    renderer_.draw(camera_.view(), camera_.projection(float(width) / float(height)), view_);
  panel_rects_.clear();
  // The others' cursors belong to the scene: drawn with the panels hidden too.
  if (!with_ui && !session_.active()) return;
  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  ImGui::NewFrame();
  if (with_ui) draw_panels();
  if (session_.active()) draw_remote_cursors();
  ImGui::Render();
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
}

// Every frame while a stroke, a replay or a benchmark runs; otherwise only on demand.
bool App::busy() const {
  return options_.bench_frames > 0 || replay_.active() || drag_ != Drag::none;
}

// One frame: input, replay, session, uploads, and drawing when something on screen changed
// (draw_schedule.h). False when the app should quit.
bool App::frame() {
  const double wait = schedule_.wait_seconds(busy(), session_.active() || session_.joining());
  if (wait > 0)
    glfwWaitEventsTimeout(wait);
  else
    glfwPollEvents();
  if (const std::optional<float> pressure = tablet_.poll()) on_pressure(*pressure);
  if (replay_.active()) replay_.step(*this);
  const auto tick_start = std::chrono::steady_clock::now();
  const double tick_cpu_start = benchmarking_frames_ ? thread_cpu_ms() : 0.0;
  session_tick();
  const auto tick_end = std::chrono::steady_clock::now();
  if (benchmarking_frames_) session_cpu_ms_.push_back(thread_cpu_ms() - tick_cpu_start);
  if (attribution_view_ && !session_.active())
    toggle_attribution_view();  // left: real colours back
  if (attribution_view_ && attribution_dirty_) {
    // The worker computes them after each merged version; until the first, keep trying.
    const auto rgb = session_.attribution_colours();
    if (rgb && rgb->size() == size_t{document_.vertex_count()} * 3) {
      renderer_.upload_colour_override(*rgb);
      attribution_dirty_ = false;
      schedule_.request(1);
    }
  }
  if (!sculptor_.dirty_vertices().empty()) schedule_.request(1);
  renderer_.upload_vertices(document_, sculptor_.dirty_vertices());
  sculptor_.clear_dirty();
  if (benchmarking_frames_) {
    using ms = std::chrono::duration<double, std::milli>;
    session_ms_.push_back(ms(tick_end - tick_start).count());
    upload_ms_.push_back(ms(std::chrono::steady_clock::now() - tick_end).count());
  }
  if (!schedule_.take(busy())) return !should_quit();
  const double draw_start = glfwGetTime();
  render(show_ui_);
  glfwSwapBuffers(window_);
  last_draw_ms_ = 1000.0 * (glfwGetTime() - draw_start);
  ++frames_drawn_;
  if (!ready_printed_) {
    std::puts("READY");
    std::fflush(stdout);
    ready_printed_ = true;
  }
  return !should_quit();
}

bool App::should_quit() const {
  if (glfwWindowShouldClose(window_)) return true;
  // A replay holds the exit back until it has run, unless it waits for a session that failed.
  const bool session_failed =
      replay_.waiting_for_session() && !session_.active() && !session_.joining();
  const bool replay_done = !replay_.loaded() || replay_.finished() || session_failed;
  return options_.exit_after_seconds && replay_done &&
         glfwGetTime() - start_time_ >= *options_.exit_after_seconds;
}

// On exit: the last versions in, then the screenshot and the save (issue 11's contract).
void App::finish() {
  if (drag_ == Drag::stroke) end_stroke();
  if (session_.active()) {
    session_.settle(2000);  // the artist's last strokes merged in and sent
    session_tick();
    renderer_.upload_vertices(document_, sculptor_.dirty_vertices());
    sculptor_.clear_dirty();
  }
  std::string error;
  if (!options_.screenshot_path.empty()) {
    render(show_ui_);
    int width = 0, height = 0;
    glfwGetFramebufferSize(window_, &width, &height);
    if (!write_screenshot(options_.screenshot_path, width, height, error)) report(error);
  }
  if (!options_.save_path.empty() && !document_.save(options_.save_path, error)) report(error);
  // For the tests: the normals the brushes, undo and merged versions kept current must be the
  // bits a full recomputation gives (a stale one is a shading seam).
  if (std::getenv("CSCULPT_APP_CHECK_NORMALS"))
    std::printf("NORMALS stale=%u bvh_loose=%u\n", document_.stale_normals(),
                bvh_.loose_boxes(document_.positions, document_.triangles));
  if (std::getenv("CSCULPT_APP_COUNT_FRAMES"))  // for the tests: drawing on demand
    std::printf("FRAMES drawn=%llu seconds=%.2f\n", frames_drawn_, glfwGetTime() - start_time_);
  if (session_.active()) {  // for scripts: where this peer's session stood when it quit
    const csc_session_stats& stats = session_.stats();
    std::string names;  // the others' names as the peer list shows them (spaces and commas as _)
    for (const SessionLink::Peer& peer : session_.peers()) {
      std::string name = peer.name;
      for (char& c : name)
        if (c == ' ' || c == ',') c = '_';
      names += (names.empty() ? "" : ",") + name;
    }
    std::printf(
        "SESSION id=%016llx merger=%016llx version=%llu members=%u submitted=%llu "
        "acknowledged=%llu "
        "presence=%zu peers=%s join_ms=%.1f host_ms=%.1f\n",
        static_cast<unsigned long long>(session_.id()),
        static_cast<unsigned long long>(stats.merger),
        static_cast<unsigned long long>(session_.version()), stats.members,
        static_cast<unsigned long long>(stats.strokes_submitted),
        static_cast<unsigned long long>(stats.strokes_acknowledged), session_.presence_seen(),
        names.c_str(), join_ms_, host_ms_);
    std::fflush(stdout);
  }
  session_.leave();
}

int App::run() {
  if (!open_window()) {
    std::fprintf(stderr, "csculpt-app: cannot open an OpenGL 3.3 window (is there a display?)\n");
    return 1;
  }
  std::string error;
  if (!renderer_.init(error)) {
    std::fprintf(stderr, "csculpt-app: %s\n", error.c_str());
    return 1;
  }
  open_start_mesh();
  layout_changed();
  if (!options_.replay_path.empty() && !replay_.load(options_.replay_path, error)) report(error);
  if (options_.host) {
    host_staging_.prepare(document_, bvh_);
    host_staging_.wait();  // as the memory is on a click, a moment after the mesh is open
    host_session();
    // The scripting contract: the invite is printed before the first frame.
    while (session_.starting_host()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
      poll_host();
    }
  }
  if (!options_.join_invite.empty()) join_session(options_.join_invite);
  if (options_.bench_frames > 0) return run_bench();
  start_time_ = glfwGetTime();
  while (frame()) {
  }
  finish();
  return 0;
}
