// Presence in the app: this artist's brush cursor goes to the session every frame (the library
// sends at most 20 a second), and the other artists' cursors are drawn as rings in their
// colours, lying on the surface under them; a cursor behind the mesh is not drawn.
#include <imgui.h>

#include <array>
#include <cmath>
#include <glm/geometric.hpp>
#include <glm/mat4x4.hpp>

#include "app.h"

namespace {

constexpr int kRingSegments = 40;

glm::vec3 vec(const std::array<float, 3>& a) {
  return {a[0], a[1], a[2]};
}

// Window pixel of a world point, or false behind the camera.
bool project(const glm::mat4& view_projection, glm::vec3 p, float width, float height,
             ImVec2& out) {
  const glm::vec4 clip = view_projection * glm::vec4(p, 1.f);
  if (clip.w <= 1e-6f) return false;
  out = ImVec2((clip.x / clip.w * 0.5f + 0.5f) * width, (0.5f - clip.y / clip.w * 0.5f) * height);
  return true;
}

}  // namespace

void App::send_presence() {
  if (!session_.active()) return;
  csc_presence presence = CSC_PRESENCE_INIT;
  RayHit hit;
  if (!over_panel(cursor_x_, cursor_y_) && pick(cursor_x_, cursor_y_, hit)) {
    for (int a = 0; a < 3; ++a) presence.position[a] = hit.point[a];
    presence.radius = dab_input(hit).radius;  // the brush's world radius there
    presence.visible = 1;
  }
  presence.active = drag_ == Drag::stroke ? 1 : 0;
  session_.set_presence(presence);
}

// The surface normal under `point` as this peer's mesh has it (the sender's may differ by its
// unmerged strokes), or false when the mesh hides the point from the camera.
bool App::surface_normal(glm::vec3 point, float radius, glm::vec3& normal) const {
  const glm::vec3 eye = camera_.eye();
  const float distance = glm::length(point - eye);
  normal = -camera_.forward();  // a screen-facing ring where the ray finds no surface
  if (distance <= 0.f) return false;
  const RayHit hit =
      bvh_.raycast(document_.positions, document_.triangles, eye, (point - eye) / distance);
  if (!hit.hit) return true;
  if (hit.distance < distance - std::max(radius, 0.01f * distance)) return false;
  glm::vec3 corner[3];
  for (int k = 0; k < 3; ++k) {
    const uint32_t v = document_.triangles[3 * size_t{hit.triangle} + size_t(k)];
    corner[k] = {document_.positions[3 * size_t{v}], document_.positions[3 * size_t{v} + 1],
                 document_.positions[3 * size_t{v} + 2]};
  }
  const glm::vec3 n = glm::cross(corner[1] - corner[0], corner[2] - corner[0]);
  if (glm::length(n) > 0.f) normal = glm::normalize(n);
  return true;
}

void App::draw_remote_cursors() {
  const int width = window_width_, height = window_height_;
  if (width <= 0 || height <= 0) return;
  const glm::mat4 view_projection =
      camera_.projection(float(width) / float(height)) * camera_.view();
  ImDrawList* draw = ImGui::GetBackgroundDrawList();  // over the mesh, under the panels
  for (const SessionLink::Cursor& cursor : session_.cursors()) {
    const glm::vec3 centre = vec(cursor.position);
    glm::vec3 normal;
    if (!surface_normal(centre, cursor.radius, normal)) continue;
    // Two axes in the surface's plane, then the ring's points in it.
    const glm::vec3 helper =
        std::abs(normal.y) < 0.9f ? glm::vec3(0.f, 1.f, 0.f) : glm::vec3(1.f, 0.f, 0.f);
    const glm::vec3 u = glm::normalize(glm::cross(normal, helper)), v = glm::cross(normal, u);
    std::array<ImVec2, kRingSegments> ring;
    bool visible = true;
    for (int i = 0; i < kRingSegments && visible; ++i) {
      const float t = 6.2831853f * float(i) / float(kRingSegments);
      const glm::vec3 p = centre + cursor.radius * (std::cos(t) * u + std::sin(t) * v);
      visible = project(view_projection, p, float(width), float(height), ring[size_t(i)]);
    }
    ImVec2 middle;
    if (!visible || !project(view_projection, centre, float(width), float(height), middle))
      continue;
    const ImU32 colour = ImGui::ColorConvertFloat4ToU32(
        ImVec4(cursor.colour[0], cursor.colour[1], cursor.colour[2], 0.95f));
    draw->AddPolyline(ring.data(), kRingSegments, colour, ImDrawFlags_Closed,
                      cursor.active ? 3.f : 2.f);
    draw->AddCircleFilled(middle, cursor.active ? 4.f : 2.5f, colour);
  }
}
