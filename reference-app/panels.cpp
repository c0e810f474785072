// The ImGui panels: tools on the left, the session on the right. Their rectangles are kept so
// a press over a panel is never a stroke (ImGui 1.86's WantCaptureMouse reads the live
// pointer, which a replay does not move).
#include <imgui.h>

#include <cstdio>
#include <cstring>

#include "app.h"

namespace {

constexpr float kPanelWidth = 300.f;
constexpr float kMargin = 10.f;

void section(const char* title) {
  ImGui::Spacing();
  ImGui::Separator();
  ImGui::TextDisabled("%s", title);
}

const char* peer_state_name(SessionLink::PeerState state) {
  switch (state) {
    case SessionLink::PeerState::live:
      return "live";
    case SessionLink::PeerState::evasive:
      return "evasive";
    case SessionLink::PeerState::left:
      return "left";
  }
  return "?";
}

// Two lines a peer: name and id; state, merger, version and round trip.
void draw_peer(const SessionLink::Peer& peer) {
  char latency[32] = "-";
  if (peer.latency_ms >= 0) std::snprintf(latency, sizeof latency, "%.1f ms", peer.latency_ms);
  ImGui::BulletText("%s  %016llx", peer.name.empty() ? "?" : peer.name.c_str(),
                    static_cast<unsigned long long>(peer.id));
  ImGui::Text("    %s%s  version %llu  rtt %s", peer_state_name(peer.state),
              peer.merger ? " (merger)" : "", static_cast<unsigned long long>(peer.version),
              latency);
}

}  // namespace

void App::draw_panels() {
  draw_tool_panel();
  draw_session_panel();
  draw_brush_cursor();
}

void App::draw_tool_panel() {
  ImGui::SetNextWindowPos(ImVec2(kMargin, kMargin), ImGuiCond_Always);
  ImGui::SetNextWindowSize(ImVec2(kPanelWidth, 0.f), ImGuiCond_Always);
  ImGui::Begin("cSculpt", nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
  ImGui::TextWrapped("%s", document_.label.c_str());
  ImGui::Text("%u vertices  %u faces", document_.vertex_count(), document_.triangle_count());
  if (!error_.empty()) {
    ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(1.f, 0.45f, 0.4f, 1.f));
    ImGui::TextWrapped("%s", error_.c_str());
    ImGui::PopStyleColor();
    if (ImGui::SmallButton("Dismiss")) error_.clear();
  }

  section("Brush");
  for (size_t i = 0; i < kBrushNames.size(); ++i) {
    if (i % 3 != 0) ImGui::SameLine();
    if (ImGui::RadioButton(kBrushNames[i], brush_.kind == static_cast<BrushKind>(i)))
      brush_.kind = static_cast<BrushKind>(i);
  }
  ImGui::SliderFloat("Radius px", &brush_.radius_pixels, 4.f, 400.f, "%.0f");
  ImGui::SliderFloat("Strength", &brush_.strength, 0.f, 1.f, "%.2f");
  int falloff = static_cast<int>(brush_.falloff);
  if (ImGui::Combo("Falloff", &falloff, kFalloffNames.data(),
                   static_cast<int>(kFalloffNames.size())))
    brush_.falloff = static_cast<Falloff>(falloff);
  ImGui::Checkbox("Invert (Ctrl)", &brush_.invert);
  ImGui::SameLine();
  ImGui::Checkbox("Front faces", &brush_.front_faces_only);
  ImGui::Text("Symmetry");
  ImGui::SameLine();
  ImGui::Checkbox("X", &brush_.symmetry[0]);
  ImGui::SameLine();
  ImGui::Checkbox("Y", &brush_.symmetry[1]);
  ImGui::SameLine();
  ImGui::Checkbox("Z", &brush_.symmetry[2]);
  ImGui::Text("Pressure ->");
  ImGui::SameLine();
  ImGui::Checkbox("radius", &brush_.pressure_radius);
  ImGui::SameLine();
  ImGui::Checkbox("strength", &brush_.pressure_strength);
  // Wrapped: the status names the devices found, wider than the panel.
  ImGui::PushStyleColor(ImGuiCol_Text, ImGui::GetStyle().Colors[ImGuiCol_TextDisabled]);
  ImGui::TextWrapped("%s", tablet_status_.c_str());
  ImGui::PopStyleColor();

  section("Paint");
  int channel = static_cast<int>(brush_.paint_channel);
  if (ImGui::Combo("Channel", &channel, kPaintChannelNames.data(),
                   static_cast<int>(kPaintChannelNames.size())))
    brush_.paint_channel = static_cast<PaintChannel>(channel);
  ImGui::ColorEdit3("Colour", &brush_.colour.x);
  ImGui::SliderFloat("Roughness", &brush_.roughness, 0.f, 1.f, "%.2f");
  ImGui::SliderFloat("Metallic", &brush_.metallic, 0.f, 1.f, "%.2f");

  section("View");
  ImGui::Checkbox("Flat (F)", &view_.flat_shading);
  ImGui::SameLine();
  ImGui::Checkbox("Wireframe (W)", &view_.wireframe);
  if (ImGui::Button("Front (1)")) camera_.set_view(ViewPreset::front);
  ImGui::SameLine();
  if (ImGui::Button("Side (3)")) camera_.set_view(ViewPreset::side);
  ImGui::SameLine();
  if (ImGui::Button("Top (7)")) camera_.set_view(ViewPreset::top);

  section("History");
  const bool in_session = session_.active();
  ImGui::BeginDisabled(in_session ? session_.undo_depth() == 0 : !history_.can_undo());
  if (ImGui::Button("Undo (Ctrl+Z)")) undo();
  ImGui::EndDisabled();
  ImGui::SameLine();
  ImGui::BeginDisabled(in_session ? session_.redo_depth() == 0 : !history_.can_redo());
  if (ImGui::Button("Redo (Ctrl+Shift+Z)")) redo();
  ImGui::EndDisabled();
  if (in_session) ImGui::TextDisabled("your own strokes; others' work stays");

  section("File");
  ImGui::InputText("##path", path_text_.data(), path_text_.size());
  if (ImGui::Button("Open")) {
    std::string error;
    if (session_.active())
      error_ = "Leave the session before opening another mesh.";
    else if (document_.load(path_text_.data(), error))
      layout_changed(), error_.clear();
    else
      report(error);
  }
  ImGui::SameLine();
  if (ImGui::Button("Save")) {
    std::string error;
    if (!document_.save(path_text_.data(), error)) report(error);
  }
  if (ImGui::CollapsingHeader("Keys")) {
    ImGui::TextWrapped(
        "Left drag: sculpt (on the mesh) or orbit (empty space, Alt). Right/middle drag: pan. "
        "Wheel: zoom. Shift: smooth. Ctrl: invert.\n"
        "D draw  G grab  I inflate  S smooth  L flatten  C crease  P pinch  T twist\n"
        "B paint colour  R roughness  M metallic\n"
        "[ ] radius  - = strength  F1-F5 falloff  E invert  V front faces  X Y Z symmetry\n"
        "1 3 7 front/side/top  F flat  W wireframe  A attribution (session)  Tab hide panels\n"
        "Ctrl+Z / Ctrl+Shift+Z undo / redo (your own strokes, also in a session)");
  }
  // Frames are drawn on demand (draw_schedule.h): a rate would count the idle sleeps.
  ImGui::Text("last frame drawn in %.1f ms", last_draw_ms_);
  panel_rects_.push_back({ImGui::GetWindowPos().x, ImGui::GetWindowPos().y,
                          ImGui::GetWindowSize().x, ImGui::GetWindowSize().y});
  ImGui::End();
}

void App::draw_session_panel() {
  const float x = ImGui::GetIO().DisplaySize.x - kPanelWidth - kMargin;
  ImGui::SetNextWindowPos(ImVec2(x, kMargin), ImGuiCond_Always);
  ImGui::SetNextWindowSize(ImVec2(kPanelWidth, 0.f), ImGuiCond_Always);
  ImGui::Begin("Session", nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
  ImGui::TextWrapped("Status: %s", session_.status().c_str());
  if (session_.joining()) {
    ImGui::TextWrapped("Waiting for the session's mesh...");
  } else if (session_.starting_host()) {
    ImGui::TextWrapped("Starting the session...");  // no invite to copy yet
  } else if (!session_.active()) {
    if (ImGui::Button("Host a session")) host_session();
    ImGui::InputTextWithHint("##invite", "paste an invite", join_text_.data(), join_text_.size());
    ImGui::SameLine();
    if (ImGui::Button("Join")) join_session(join_text_.data());
    // Below the buttons, so that hosting and joining stay where scripts and habits find them.
    ImGui::InputTextWithHint("Name", options_.name.c_str(), name_text_.data(), name_text_.size());
    if (options_.bind.empty())
      ImGui::Checkbox("Other machines can join", &reachable_);
    else
      ImGui::TextWrapped("Listening on %s", options_.bind.c_str());
  } else {
    // The buttons first, where "Host a session" was: the invite's length never moves them.
    const csc_session_stats& stats = session_.stats();
    if (ImGui::Button("Copy invite")) glfwSetClipboardString(window_, session_.invite());
    ImGui::SameLine();
    if (ImGui::Button("Leave")) session_.leave();
    ImGui::TextWrapped("Invite: %.40s...", session_.invite());
    // Where the others reach this peer: the address an artist checks against their network.
    if (const char* at = std::strrchr(session_.invite(), '@')) ImGui::TextWrapped("at %s", at + 1);
    ImGui::Text("me %016llx", static_cast<unsigned long long>(session_.id()));
    ImGui::Text("merger %016llx%s", static_cast<unsigned long long>(stats.merger),
                stats.merger == session_.id() ? " (me)" : "");
    ImGui::Text("version %llu  members %u", static_cast<unsigned long long>(session_.version()),
                stats.members);
    ImGui::Text("strokes sent %llu, merged %llu",
                static_cast<unsigned long long>(stats.strokes_submitted),
                static_cast<unsigned long long>(stats.strokes_acknowledged));
    ImGui::Text("sent %.1f KB  merges %llu (%.1f ms)", double(stats.submit_bytes) / 1024.0,
                static_cast<unsigned long long>(stats.merges), stats.merge_ms_mean);
    // Creases this peer's merges made that no artist did: the merge's one visible failure.
    if (stats.merges > 0)
      ImGui::Text("faces my merges turned over: %llu",
                  static_cast<unsigned long long>(stats.folds_introduced));
    for (const SessionLink::Peer& peer : session_.peers()) draw_peer(peer);
    bool attribution = attribution_view_;
    if (ImGui::Checkbox("Attribution view (A)", &attribution)) toggle_attribution_view();
  }
  for (const std::string& message : session_.messages())
    ImGui::TextWrapped("- %s", message.c_str());
  panel_rects_.push_back({ImGui::GetWindowPos().x, ImGui::GetWindowPos().y,
                          ImGui::GetWindowSize().x, ImGui::GetWindowSize().y});
  ImGui::End();
}

void App::draw_brush_cursor() {
  if (over_panel(cursor_x_, cursor_y_)) return;
  const float radius = brush_.radius_pixels * (brush_.pressure_radius ? pressure_ : 1.f);
  const ImU32 colour =
      brush_.kind == BrushKind::paint ? IM_COL32(255, 200, 120, 200) : IM_COL32(255, 255, 255, 160);
  ImGui::GetForegroundDrawList()->AddCircle(ImVec2(float(cursor_x_), float(cursor_y_)), radius,
                                            colour, 48, 1.5f);
}
