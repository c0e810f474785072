#include "camera.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

namespace {
constexpr float kOrbitRadiansPerPixel = 0.008f;
constexpr float kMaxPitch = 1.55f;  // just short of straight up/down, where yaw would flip
}  // namespace

void OrbitCamera::frame(glm::vec3 center, float radius) {
  target_ = center;
  scene_radius_ = std::max(radius, 1e-6f);
  // The bounding box's half diagonal overstates a round mesh's size: frame a little closer.
  distance_ = scene_radius_ / std::sin(fov_y_ / 2.f) * 0.8f;
  set_view(ViewPreset::front);
}

void OrbitCamera::orbit(float dx_pixels, float dy_pixels) {
  yaw_ -= dx_pixels * kOrbitRadiansPerPixel;
  pitch_ = std::clamp(pitch_ + dy_pixels * kOrbitRadiansPerPixel, -kMaxPitch, kMaxPitch);
}

void OrbitCamera::pan(float dx_pixels, float dy_pixels, float viewport_height) {
  const glm::mat4 v = view();
  const glm::vec3 right(v[0][0], v[1][0], v[2][0]);
  const glm::vec3 up(v[0][1], v[1][1], v[2][1]);
  const float scale = world_per_pixel(distance_, viewport_height);
  target_ += (-dx_pixels * right + dy_pixels * up) * scale;
}

void OrbitCamera::zoom(float steps) {
  distance_ =
      std::clamp(distance_ * std::pow(0.9f, steps), scene_radius_ * 0.05f, scene_radius_ * 50.f);
}

void OrbitCamera::set_view(ViewPreset preset) {
  switch (preset) {
    case ViewPreset::front:
      yaw_ = 0.f, pitch_ = 0.f;
      break;
    case ViewPreset::side:
      yaw_ = 1.5707964f, pitch_ = 0.f;
      break;
    case ViewPreset::top:
      yaw_ = 0.f, pitch_ = kMaxPitch;
      break;
  }
}

glm::vec3 OrbitCamera::forward() const {
  // Yaw 0, pitch 0: looking from +Z towards -Z. Yaw turns to look from +X (side view).
  return -glm::vec3(std::cos(pitch_) * std::sin(yaw_), std::sin(pitch_),
                    std::cos(pitch_) * std::cos(yaw_));
}

glm::vec3 OrbitCamera::eye() const {
  return target_ - forward() * distance_;
}

glm::mat4 OrbitCamera::view() const {
  return glm::lookAt(eye(), target_, glm::vec3(0.f, 1.f, 0.f));
}

glm::mat4 OrbitCamera::projection(float aspect) const {
  const float near_plane = std::max(distance_ - scene_radius_ * 4.f, distance_ * 0.01f);
  return glm::perspective(fov_y_, aspect, near_plane, distance_ + scene_radius_ * 4.f);
}

Ray OrbitCamera::ray_through(float x, float y, float width, float height) const {
  const float tan_half = std::tan(fov_y_ / 2.f);
  const float ndc_x = (2.f * (x + 0.5f) / width - 1.f) * tan_half * (width / height);
  const float ndc_y = (1.f - 2.f * (y + 0.5f) / height) * tan_half;
  const glm::mat4 v = view();
  const glm::vec3 right(v[0][0], v[1][0], v[2][0]);
  const glm::vec3 up(v[0][1], v[1][1], v[2][1]);
  return {eye(), glm::normalize(forward() + right * ndc_x + up * ndc_y)};
}

float OrbitCamera::world_per_pixel(float depth, float viewport_height) const {
  return 2.f * depth * std::tan(fov_y_ / 2.f) / viewport_height;
}

glm::vec3 OrbitCamera::point_on_view_plane(float x, float y, float width, float height,
                                           glm::vec3 anchor) const {
  const Ray ray = ray_through(x, y, width, height);
  const glm::vec3 normal = forward();
  const float along = glm::dot(anchor - ray.origin, normal) / glm::dot(ray.direction, normal);
  return ray.origin + ray.direction * along;
}
