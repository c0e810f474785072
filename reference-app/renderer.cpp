#include "renderer.h"

#include <glm/gtc/type_ptr.hpp>
#include <glm/matrix.hpp>

#include <algorithm>
#include <array>
#include <cstdint>
#include <iterator>

namespace {

// Merge runs of changed vertices separated by fewer unchanged ones than this: one larger
// glBufferSubData is cheaper than many tiny ones.
constexpr uint32_t kRunGap = 32;

// Floats per vertex of each attribute: position, normal, albedo, roughness, metallic.
constexpr GLint kWidths[] = {3, 3, 3, 1, 1};

// Fills the index buffer with the clusters' triangles (bound to a target no vertex array owns:
// this may run in a context of another thread, with no vertex array bound).
void fill_indices(GLuint buffer, const DrawClusters& clusters) {
  glBindBuffer(GL_COPY_WRITE_BUFFER, buffer);
  glBufferData(GL_COPY_WRITE_BUFFER,
               static_cast<GLsizeiptr>(clusters.draw_order().size() * sizeof(uint32_t)),
               clusters.draw_order().data(), GL_STATIC_DRAW);
  glBindBuffer(GL_COPY_WRITE_BUFFER, 0);
}

// Fills the attribute buffers `buffers` with the document's values (glBufferData: new storage).
// A material channel the mesh lacks is drawn as 0.5, from `constant`, filled only then.
void fill_attributes(const GLuint* buffers, const MeshDocument& document,
                     std::vector<float>& constant) {
  if (document.albedo < 0 || document.roughness < 0 || document.metallic < 0)
    constant.assign(size_t{document.vertex_count()} * 3, 0.5f);
  auto channel = [&](int index) {
    return index >= 0 ? document.channels[index].values.data() : constant.data();
  };
  const std::array<const float*, std::size(kWidths)> data = {
      document.positions.data(), document.normals.data(), channel(document.albedo),
      channel(document.roughness), channel(document.metallic)};
  for (size_t a = 0; a < data.size(); ++a) {
    glBindBuffer(GL_ARRAY_BUFFER, buffers[a]);
    glBufferData(GL_ARRAY_BUFFER,
                 static_cast<GLsizeiptr>(size_t{document.vertex_count()} *
                                         static_cast<size_t>(kWidths[a]) * sizeof(float)),
                 data[a], GL_DYNAMIC_DRAW);
  }
}

constexpr const char* kVertexShader = R"(#version 330 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec3 a_albedo;
layout(location = 3) in float a_roughness;
layout(location = 4) in float a_metallic;
uniform mat4 u_view;
uniform mat4 u_projection;
out vec3 v_position;
out vec3 v_normal;
out vec3 v_albedo;     // linear (decoded from sRGB here, once per vertex)
out float v_shininess;  // Blinn-Phong exponent of the roughness
out float v_metallic;
void main() {
  vec4 p = u_view * vec4(a_position, 1.0);
  v_position = p.xyz;
  v_normal = mat3(u_view) * a_normal;
  v_albedo = pow(clamp(a_albedo, 0.0, 1.0), vec3(2.2));
  float alpha = max(a_roughness * a_roughness, 0.02);
  v_shininess = 2.0 / (alpha * alpha) - 2.0;
  v_metallic = a_metallic;
  gl_Position = u_projection * p;
}
)";

// A small PBR-style preview: Lambert diffuse for the albedo a metal lacks, Blinn-Phong
// specular whose sharpness follows roughness (alpha = roughness^2), tinted by metallic, under
// a key, a fill and a head light. On llvmpipe the fragments are a third of a frame and every
// pow() is a log and an exp: the albedo's sRGB decode and the exponent are per vertex, and the
// encode is 1.138 sqrt(c) - 0.138 c, within 0.011 (3 of 255 levels) of c^(1/2.2) on [0, 1].
constexpr const char* kFragmentShader = R"(#version 330 core
in vec3 v_position;
in vec3 v_normal;
in vec3 v_albedo;
in float v_shininess;
in float v_metallic;
uniform bool u_flat;
uniform bool u_wire;
out vec4 frag_colour;
vec3 light(vec3 n, vec3 v, vec3 l, vec3 colour, vec3 diffuse, vec3 f0, float shininess) {
  float nl = max(dot(n, l), 0.0);
  vec3 h = normalize(l + v);
  float spec = pow(max(dot(n, h), 0.0), shininess) * (shininess + 8.0) / 25.0;
  return colour * nl * (diffuse + f0 * spec);
}
void main() {
  if (u_wire) { frag_colour = vec4(0.08, 0.08, 0.1, 1.0); return; }
  vec3 n = u_flat ? normalize(cross(dFdx(v_position), dFdy(v_position))) : normalize(v_normal);
  vec3 v = normalize(-v_position);
  if (dot(n, v) < 0.0) n = -n;
  float shininess = v_shininess;
  vec3 f0 = mix(vec3(0.04), v_albedo, v_metallic);
  vec3 diffuse = v_albedo * (1.0 - v_metallic);
  vec3 c = vec3(0.10) * diffuse + vec3(0.06) * f0;
  c += light(n, v, normalize(vec3(0.5, 0.7, 0.6)), vec3(0.9), diffuse, f0, shininess);
  c += light(n, v, normalize(vec3(-0.7, 0.1, 0.4)), vec3(0.35, 0.38, 0.45), diffuse, f0, shininess);
  c += light(n, v, vec3(0.0, 0.0, 1.0), vec3(0.25), diffuse, f0, shininess);
  vec3 s = sqrt(c);
  frag_colour = vec4(1.138 * s - 0.138 * c, 1.0);
}
)";

bool compile(GLuint shader, const char* source, std::string& error) {
  glShaderSource(shader, 1, &source, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (ok) return true;
  char log[2048];
  glGetShaderInfoLog(shader, sizeof log, nullptr, log);
  error = std::string("shader: ") + log;
  return false;
}

}  // namespace

void Renderer::release() {
  if (!program_) return;
  glDeleteBuffers(kAttributeCount, buffers_);
  glDeleteBuffers(1, &index_buffer_);
  glDeleteVertexArrays(1, &vao_);
  glDeleteProgram(program_);
  program_ = 0;
  index_count_ = 0;
}

bool Renderer::init(std::string& error) {
  const GLuint vs = glCreateShader(GL_VERTEX_SHADER), fs = glCreateShader(GL_FRAGMENT_SHADER);
  const bool compiled = compile(vs, kVertexShader, error) && compile(fs, kFragmentShader, error);
  if (compiled) {
    program_ = glCreateProgram();
    glAttachShader(program_, vs);
    glAttachShader(program_, fs);
    glLinkProgram(program_);
  }
  glDeleteShader(vs);
  glDeleteShader(fs);
  if (!compiled) return false;
  u_view_ = glGetUniformLocation(program_, "u_view");
  u_projection_ = glGetUniformLocation(program_, "u_projection");
  u_flat_ = glGetUniformLocation(program_, "u_flat");
  u_wire_ = glGetUniformLocation(program_, "u_wire");
  glGenVertexArrays(1, &vao_);
  glGenBuffers(kAttributeCount, buffers_);
  glGenBuffers(1, &index_buffer_);
  attach_buffers();
  return true;
}

void Renderer::attach_buffers() {
  glBindVertexArray(vao_);
  for (GLuint a = 0; a < kAttributeCount; ++a) {
    glBindBuffer(GL_ARRAY_BUFFER, buffers_[a]);
    glVertexAttribPointer(a, kWidths[a], GL_FLOAT, GL_FALSE, 0, nullptr);
    glEnableVertexAttribArray(a);
  }
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, index_buffer_);
  glBindVertexArray(0);
}

MeshBuffers Renderer::fill_buffers(const MeshDocument& document, const DrawClusters& clusters) {
  MeshBuffers out;
  glGenBuffers(1, &out.index);
  glGenBuffers(kAttributeCount, out.attributes);
  fill_indices(out.index, clusters);
  std::vector<float> constant;
  fill_attributes(out.attributes, document, constant);
  glFinish();
  return out;
}

void Renderer::adopt_mesh(const MeshDocument& document, DrawClusters clusters,
                          MeshBuffers buffers) {
  clusters_ = std::move(clusters);
  glDeleteBuffers(kAttributeCount, buffers_);
  glDeleteBuffers(1, &index_buffer_);
  index_buffer_ = buffers.index;
  std::copy(std::begin(buffers.attributes), std::end(buffers.attributes), buffers_);
  attach_buffers();
  index_count_ = static_cast<GLsizei>(document.triangles.size());
  colour_overridden_ = false;
  vertex_count_ = document.vertex_count();
  upload_marks_.resize(vertex_count_);
  uploaded_last_ = vertex_count_;
}

void Renderer::upload_mesh(const MeshDocument& document, DrawClusters clusters) {
  clusters_ = std::move(clusters);
  fill_indices(index_buffer_, clusters_);
  index_count_ = static_cast<GLsizei>(document.triangles.size());
  upload_values(document);
}

void Renderer::upload_values(const MeshDocument& document) {
  colour_overridden_ = false;
  vertex_count_ = document.vertex_count();
  upload_marks_.resize(vertex_count_);
  fill_attributes(buffers_, document, constant_);
  uploaded_last_ = vertex_count_;
}

void Renderer::upload_range(const MeshDocument& document, uint32_t first, uint32_t count) {
  auto upload = [&](int attribute, const float* values, size_t width) {
    if (!values) return;
    glBindBuffer(GL_ARRAY_BUFFER, buffers_[attribute]);
    glBufferSubData(GL_ARRAY_BUFFER, static_cast<GLintptr>(first * width * sizeof(float)),
                    static_cast<GLsizeiptr>(count * width * sizeof(float)), values + first * width);
  };
  auto channel = [&](int index) {
    return index >= 0 ? document.channels[index].values.data() : nullptr;
  };
  upload(kPosition, document.positions.data(), 3);
  upload(kNormal, document.normals.data(), 3);
  if (!colour_overridden_) upload(kAlbedo, channel(document.albedo), 3);
  upload(kRoughness, channel(document.roughness), 1);
  upload(kMetallic, channel(document.metallic), 1);
}

void Renderer::upload_vertices(const MeshDocument& document, std::span<const uint32_t> vertices) {
  uploaded_last_ = 0;
  // Called every frame: the clusters a change left stale are recomputed a few per frame.
  clusters_.mark_moved(vertices);
  clusters_.refit_stale(document.positions, document.triangles);
  if (vertices.empty()) return;
  // Runs of vertices in increasing order, merged across small gaps.
  for (uint32_t v : vertices) upload_marks_.mark(v);
  uint32_t first = UINT32_MAX, last = 0;
  auto flush = [&] {
    upload_range(document, first, last - first + 1);
    uploaded_last_ += last - first + 1;
  };
  upload_marks_.take_in_order([&](uint32_t v) {
    if (first != UINT32_MAX && v - last <= kRunGap) {
      last = v;
      return;
    }
    if (first != UINT32_MAX) flush();
    first = last = v;
  });
  flush();
}

void Renderer::upload_colour_override(std::span<const float> rgb) {
  colour_overridden_ = true;
  glBindBuffer(GL_ARRAY_BUFFER, buffers_[kAlbedo]);
  glBufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(rgb.size() * sizeof(float)),
                  rgb.data());
}

// Only the clusters in view and, with back-face culling, not facing away: GL would discard
// the rest itself, but only after transforming every vertex of it.
void Renderer::find_visible(const glm::mat4& view, const glm::mat4& projection,
                            bool cull_back_faces) {
  const glm::vec3 eye(glm::inverse(view)[3]);
  clusters_.visible_ranges(projection * view, eye, cull_back_faces, range_first_, range_count_);
  draw_counts_.clear();
  draw_offsets_.clear();
  drawn_last_ = 0;
  for (size_t i = 0; i < range_first_.size(); ++i) {
    draw_counts_.push_back(static_cast<GLsizei>(range_count_[i]));
    draw_offsets_.push_back(
        reinterpret_cast<const void*>(uintptr_t{range_first_[i]} * sizeof(uint32_t)));
    drawn_last_ += range_count_[i] / 3;
  }
}

void Renderer::draw_visible() const {
  if (draw_counts_.empty()) return;
  glMultiDrawElements(GL_TRIANGLES, draw_counts_.data(), GL_UNSIGNED_INT, draw_offsets_.data(),
                      static_cast<GLsizei>(draw_counts_.size()));
}

void Renderer::draw(const glm::mat4& view, const glm::mat4& projection,
                    const ViewSettings& settings) {
  if (index_count_ == 0) return;
  find_visible(view, projection, settings.backface_culling);
  glEnable(GL_DEPTH_TEST);
  if (settings.backface_culling)
    glEnable(GL_CULL_FACE);
  else
    glDisable(GL_CULL_FACE);
  glCullFace(GL_BACK);
  glUseProgram(program_);
  glUniformMatrix4fv(u_view_, 1, GL_FALSE, glm::value_ptr(view));
  glUniformMatrix4fv(u_projection_, 1, GL_FALSE, glm::value_ptr(projection));
  glUniform1i(u_flat_, settings.flat_shading);
  glUniform1i(u_wire_, 0);
  glBindVertexArray(vao_);
  if (settings.wireframe) {  // push the fill back so the lines drawn over it win the depth test
    glEnable(GL_POLYGON_OFFSET_FILL);
    glPolygonOffset(1.f, 1.f);
  }
  draw_visible();
  if (settings.wireframe) {
    glDisable(GL_POLYGON_OFFSET_FILL);
    glUniform1i(u_wire_, 1);
    glPolygonMode(GL_FRONT_AND_BACK, GL_LINE);
    draw_visible();
    glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
  }
  glBindVertexArray(0);
  glUseProgram(0);
}
