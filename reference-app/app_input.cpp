// Mouse and keys: strokes, the camera and the shortcuts. Every path here is reached by the
// real GLFW callbacks and by --replay alike.
#include <imgui.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <glm/geometric.hpp>

#include "app.h"

namespace {

// Dabs are placed along the cursor's path at this fraction of the brush radius, so a stroke
// is the same whatever the frame rate or the number of cursor events.
constexpr float kDabSpacing = 0.2f;

}  // namespace

bool App::over_panel(double x, double y) const {
  return std::any_of(panel_rects_.begin(), panel_rects_.end(), [&](const Rect& r) {
    return x >= r.x && x < r.x + r.w && y >= r.y && y < r.y + r.h;
  });
}

bool App::pick(double x, double y, RayHit& hit) const {
  const Ray ray =
      camera_.ray_through(float(x), float(y), float(window_width_), float(window_height_));
  hit = bvh_.raycast(document_.positions, document_.triangles, ray.origin, ray.direction);
  return hit.hit;
}

DabInput App::dab_input(const RayHit& hit) const {
  const glm::vec3 eye = camera_.eye();
  const float depth = glm::dot(hit.point - eye, camera_.forward());
  const float radius_pixels = brush_.radius_pixels * (brush_.pressure_radius ? pressure_ : 1.f);
  DabInput input;
  input.center = hit.point;
  input.view_direction = glm::normalize(hit.point - eye);
  input.radius = radius_pixels * camera_.world_per_pixel(depth, float(window_height_));
  input.strength = brush_.strength * (brush_.pressure_strength ? pressure_ : 1.f);
  input.invert = stroke_invert_;
  input.kind = stroke_kind_;
  return input;
}

void App::begin_stroke(int mods) {
  RayHit hit;
  // Alt+drag, or a press on empty space, orbits (as in Blender and SculptGL).
  if ((mods & GLFW_MOD_ALT) || !pick(cursor_x_, cursor_y_, hit)) {
    drag_ = Drag::orbit;
    return;
  }
  drag_ = Drag::stroke;
  stroke_kind_ = (mods & GLFW_MOD_SHIFT) ? BrushKind::smooth : brush_.kind;
  stroke_invert_ = brush_.invert != ((mods & GLFW_MOD_CONTROL) != 0);
  history_.begin_stroke();
  const DabInput input = dab_input(hit);
  if (stroke_kind_ == BrushKind::grab) {
    grab_anchor_ = hit.point;
    sculptor_.grab_begin(input, brush_);
  } else {
    sculptor_.dab(input, brush_);
  }
}

void App::continue_stroke() {
  const int width = window_width_, height = window_height_;
  if (stroke_kind_ == BrushKind::grab) {
    const glm::vec3 target = camera_.point_on_view_plane(float(cursor_x_), float(cursor_y_),
                                                         float(width), float(height), grab_anchor_);
    sculptor_.grab_move(target - grab_anchor_);
    drag_x_ = cursor_x_, drag_y_ = cursor_y_;
    return;
  }
  const double spacing = std::max(1.0, double(brush_.radius_pixels) * kDabSpacing);
  const double dx = cursor_x_ - drag_x_, dy = cursor_y_ - drag_y_;
  const double length = std::sqrt(dx * dx + dy * dy);
  if (length < spacing) return;  // keep the last dab as the anchor until a full step is made
  const int steps = static_cast<int>(length / spacing);
  for (int i = 1; i <= steps; ++i) {
    const double x = drag_x_ + dx * (spacing * i / length),
                 y = drag_y_ + dy * (spacing * i / length);
    const auto start = std::chrono::steady_clock::now();
    RayHit hit;
    if (pick(x, y, hit)) sculptor_.dab(dab_input(hit), brush_);
    if (benchmarking_)
      dab_ms_.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
              .count());
  }
  drag_x_ += dx * (spacing * steps / length);
  drag_y_ += dy * (spacing * steps / length);
}

void App::end_stroke() {
  if (drag_ == Drag::stroke) {
    sculptor_.grab_end();
    sculptor_.stroke_ended();
    history_.end_stroke(document_);
    // Handed over when it ends (sent then, never mid-stroke), with what undo needs.
    if (session_.active() && history_.has_last())
      session_.hand_stroke(history_.last_vertices(), history_.last_before(), history_.last_after());
  }
  drag_ = Drag::none;
}

void App::on_cursor(double x, double y) {
  const double dx = x - cursor_x_, dy = y - cursor_y_;
  cursor_x_ = x, cursor_y_ = y;
  switch (drag_) {
    case Drag::stroke:
      continue_stroke();
      break;
    case Drag::orbit:
      camera_.orbit(float(dx), float(dy));
      break;
    case Drag::pan: {
      camera_.pan(float(dx), float(dy), float(window_height_));
      break;
    }
    case Drag::none:
      break;
  }
}

void App::on_button(int button, int action, int mods) {
  if (action == GLFW_RELEASE) {
    if (drag_ != Drag::none) end_stroke();
    return;
  }
  if (action != GLFW_PRESS || drag_ != Drag::none || over_panel(cursor_x_, cursor_y_)) return;
  drag_x_ = cursor_x_, drag_y_ = cursor_y_;
  if (button == GLFW_MOUSE_BUTTON_LEFT)
    begin_stroke(mods);
  else if (button == GLFW_MOUSE_BUTTON_RIGHT || button == GLFW_MOUSE_BUTTON_MIDDLE)
    drag_ = Drag::pan;
}

void App::on_scroll(double dy) {
  if (!over_panel(cursor_x_, cursor_y_)) camera_.zoom(float(dy));
}

void App::undo() {
  if (session_.active()) return session_step(false);
  if (history_.undo(document_, undo_changed_)) sculptor_.refresh_after_change(undo_changed_, true);
}

void App::redo() {
  if (session_.active()) return session_step(true);
  if (history_.redo(document_, undo_changed_)) sculptor_.refresh_after_change(undo_changed_, true);
}

// In a session the artist's own strokes are undone by the session (merged with everyone's
// work since) and sent like a stroke; the local history only records them.
void App::session_step(bool redo) {
  if (drag_ != Drag::stroke) session_.request_step(redo);  // the result comes back as changes
}

void App::on_key(int key, int action, int mods) {
  if (action != GLFW_PRESS && action != GLFW_REPEAT) return;
  if (imgui_ready_ && ImGui::GetIO().WantTextInput) return;  // typing an invite or a path
  if (drag_ == Drag::stroke) return;                         // no tool change inside a stroke
  shortcut(key, mods);
}

bool App::shortcut(int key, int mods) {
  const bool ctrl = mods & GLFW_MOD_CONTROL, shift = mods & GLFW_MOD_SHIFT;
  if (ctrl) {
    if (key == GLFW_KEY_Z)
      shift ? redo() : undo();
    else if (key == GLFW_KEY_Y)
      redo();
    else
      return false;
    return true;
  }
  auto select = [&](BrushKind kind) { brush_.kind = kind; };
  auto paint = [&](PaintChannel channel) {
    brush_.kind = BrushKind::paint;
    brush_.paint_channel = channel;
  };
  switch (key) {
    case GLFW_KEY_1:
    case GLFW_KEY_KP_1:
      camera_.set_view(ViewPreset::front);
      break;
    case GLFW_KEY_3:
    case GLFW_KEY_KP_3:
      camera_.set_view(ViewPreset::side);
      break;
    case GLFW_KEY_7:
    case GLFW_KEY_KP_7:
      camera_.set_view(ViewPreset::top);
      break;
    case GLFW_KEY_D:
      select(BrushKind::draw);
      break;
    case GLFW_KEY_G:
      select(BrushKind::grab);
      break;
    case GLFW_KEY_I:
      select(BrushKind::inflate);
      break;
    case GLFW_KEY_S:
      select(BrushKind::smooth);
      break;
    case GLFW_KEY_L:
      select(BrushKind::flatten);
      break;
    case GLFW_KEY_C:
      select(BrushKind::crease);
      break;
    case GLFW_KEY_P:
      select(BrushKind::pinch);
      break;
    case GLFW_KEY_T:
      select(BrushKind::twist);
      break;
    case GLFW_KEY_B:
      paint(PaintChannel::albedo);
      break;
    case GLFW_KEY_R:
      paint(PaintChannel::roughness);
      break;
    case GLFW_KEY_M:
      paint(PaintChannel::metallic);
      break;
    case GLFW_KEY_W:
      view_.wireframe = !view_.wireframe;
      break;
    case GLFW_KEY_F:
      view_.flat_shading = !view_.flat_shading;
      break;
    case GLFW_KEY_X:
      brush_.symmetry[0] = !brush_.symmetry[0];
      break;
    case GLFW_KEY_Y:
      brush_.symmetry[1] = !brush_.symmetry[1];
      break;
    case GLFW_KEY_Z:
      brush_.symmetry[2] = !brush_.symmetry[2];
      break;
    case GLFW_KEY_E:
      brush_.invert = !brush_.invert;
      break;
    case GLFW_KEY_V:
      brush_.front_faces_only = !brush_.front_faces_only;
      break;
    case GLFW_KEY_LEFT_BRACKET:
      brush_.radius_pixels = std::max(4.f, brush_.radius_pixels * 0.8f);
      break;
    case GLFW_KEY_RIGHT_BRACKET:
      brush_.radius_pixels = std::min(400.f, brush_.radius_pixels * 1.25f);
      break;
    case GLFW_KEY_MINUS:
      brush_.strength = std::max(0.05f, brush_.strength - 0.1f);
      break;
    case GLFW_KEY_EQUAL:
      brush_.strength = std::min(1.f, brush_.strength + 0.1f);
      break;
    case GLFW_KEY_F1:
    case GLFW_KEY_F2:
    case GLFW_KEY_F3:
    case GLFW_KEY_F4:
    case GLFW_KEY_F5:
      brush_.falloff = static_cast<Falloff>(key - GLFW_KEY_F1);
      break;
    case GLFW_KEY_TAB:
      show_ui_ = !show_ui_;
      break;
    case GLFW_KEY_A:
      toggle_attribution_view();
      break;
    default:
      return false;
  }
  return true;
}
