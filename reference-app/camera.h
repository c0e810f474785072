// An orbit camera around a target point: yaw/pitch/distance, perspective projection.
#pragma once

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

enum class ViewPreset { front, side, top };

struct Ray {
  glm::vec3 origin, direction;
};

class OrbitCamera {
 public:
  /** Centres the view on a sphere of `radius` around `center`, looking from the front. */
  void frame(glm::vec3 center, float radius);
  void orbit(float dx_pixels, float dy_pixels);
  void pan(float dx_pixels, float dy_pixels, float viewport_height);
  void zoom(float steps);
  void set_view(ViewPreset preset);

  glm::vec3 eye() const;
  glm::mat4 view() const;
  glm::mat4 projection(float aspect) const;
  /** The ray through pixel (x, y) (window coordinates, y down). */
  Ray ray_through(float x, float y, float width, float height) const;
  /** World length of `pixels` at `depth` along the view direction. */
  float world_per_pixel(float depth, float viewport_height) const;
  /** The point under pixel (x, y) on the plane through `anchor` facing the camera. */
  glm::vec3 point_on_view_plane(float x, float y, float width, float height,
                                glm::vec3 anchor) const;
  glm::vec3 forward() const;

 private:
  glm::vec3 target_{0.f};
  float distance_ = 3.f;
  float yaw_ = 0.f, pitch_ = 0.f;  // radians; yaw 0 looks along -Z
  float fov_y_ = 0.7853982f;       // 45 degrees
  float scene_radius_ = 1.f;
};
