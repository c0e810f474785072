/* Prints the layout of every struct of csculpt.h and the values of its _INIT macros, as the
 * C compiler sees them, for test_binding.py to compare with the ctypes mirrors in csculpt.py.
 *   size STRUCT BYTES
 *   field STRUCT FIELD OFFSET BYTES
 *   init STRUCT FIELD VALUE          (numeric fields of STRUCT's CSC_*_INIT) */
#include <stddef.h>
#include <stdio.h>

#include "csculpt.h"

#define SIZE(T) printf("size %s %zu\n", #T, sizeof(T))
#define FIELD(T, f) printf("field %s %s %zu %zu\n", #T, #f, offsetof(T, f), sizeof(((T*)0)->f))
#define INIT(T, MACRO, f)                                   \
  do {                                                      \
    const T value_ = MACRO;                                 \
    printf("init %s %s %.17g\n", #T, #f, (double)value_.f); \
  } while (0)

int main(void) {
  SIZE(csc_channel_desc);
  FIELD(csc_channel_desc, name);
  FIELD(csc_channel_desc, width);
  FIELD(csc_channel_desc, linearisation);
  FIELD(csc_channel_desc, min_value);
  FIELD(csc_channel_desc, max_value);

  SIZE(csc_mesh_desc);
  FIELD(csc_mesh_desc, struct_size);
  FIELD(csc_mesh_desc, vertex_count);
  FIELD(csc_mesh_desc, positions);
  FIELD(csc_mesh_desc, triangle_count);
  FIELD(csc_mesh_desc, triangles);
  FIELD(csc_mesh_desc, channel_count);
  FIELD(csc_mesh_desc, channels);
  FIELD(csc_mesh_desc, channel_values);
  INIT(csc_mesh_desc, CSC_MESH_DESC_INIT, struct_size);
  INIT(csc_mesh_desc, CSC_MESH_DESC_INIT, vertex_count);

  SIZE(csc_channel_view);
  FIELD(csc_channel_view, struct_size);
  FIELD(csc_channel_view, desc);
  FIELD(csc_channel_view, values);
  INIT(csc_channel_view, CSC_CHANNEL_VIEW_INIT, struct_size);

  SIZE(csc_hierarchy_options);
  FIELD(csc_hierarchy_options, struct_size);
  FIELD(csc_hierarchy_options, max_parents);
  INIT(csc_hierarchy_options, CSC_HIERARCHY_OPTIONS_INIT, struct_size);
  INIT(csc_hierarchy_options, CSC_HIERARCHY_OPTIONS_INIT, max_parents);

  SIZE(csc_hierarchy_stats);
  FIELD(csc_hierarchy_stats, struct_size);
  FIELD(csc_hierarchy_stats, vertices);
  FIELD(csc_hierarchy_stats, faces);
  FIELD(csc_hierarchy_stats, levels);
  FIELD(csc_hierarchy_stats, nodes);
  FIELD(csc_hierarchy_stats, node_ratio);
  FIELD(csc_hierarchy_stats, mean_level_ratio);
  FIELD(csc_hierarchy_stats, top_nodes);
  INIT(csc_hierarchy_stats, CSC_HIERARCHY_STATS_INIT, struct_size);

  SIZE(csc_vertex_arrays);
  FIELD(csc_vertex_arrays, struct_size);
  FIELD(csc_vertex_arrays, vertex_count);
  FIELD(csc_vertex_arrays, positions);
  FIELD(csc_vertex_arrays, channel_count);
  FIELD(csc_vertex_arrays, channels);
  INIT(csc_vertex_arrays, CSC_VERTEX_ARRAYS_INIT, struct_size);

  SIZE(csc_diff_info);
  FIELD(csc_diff_info, struct_size);
  FIELD(csc_diff_info, vertex_count);
  FIELD(csc_diff_info, touched_vertices);
  FIELD(csc_diff_info, position_changes);
  FIELD(csc_diff_info, channel_count);
  FIELD(csc_diff_info, digest);
  INIT(csc_diff_info, CSC_DIFF_INFO_INIT, struct_size);

  SIZE(csc_message_info);
  FIELD(csc_message_info, struct_size);
  FIELD(csc_message_info, protocol);
  FIELD(csc_message_info, base_version);
  FIELD(csc_message_info, sequence);
  FIELD(csc_message_info, vertex_count);
  FIELD(csc_message_info, author);
  INIT(csc_message_info, CSC_MESSAGE_INFO_INIT, struct_size);

  SIZE(csc_encode_options);
  FIELD(csc_encode_options, struct_size);
  FIELD(csc_encode_options, base_version);
  FIELD(csc_encode_options, sequence);
  FIELD(csc_encode_options, author);
  FIELD(csc_encode_options, position_tolerance);
  FIELD(csc_encode_options, position_scale);
  FIELD(csc_encode_options, channel_tolerance);
  INIT(csc_encode_options, CSC_ENCODE_OPTIONS_INIT, struct_size);
  INIT(csc_encode_options, CSC_ENCODE_OPTIONS_INIT, base_version);
  INIT(csc_encode_options, CSC_ENCODE_OPTIONS_INIT, sequence);
  INIT(csc_encode_options, CSC_ENCODE_OPTIONS_INIT, position_tolerance);
  INIT(csc_encode_options, CSC_ENCODE_OPTIONS_INIT, position_scale);
  INIT(csc_encode_options, CSC_ENCODE_OPTIONS_INIT, channel_tolerance);

  SIZE(csc_merge_options);
  FIELD(csc_merge_options, struct_size);
  FIELD(csc_merge_options, method);
  FIELD(csc_merge_options, use_frame);
  FIELD(csc_merge_options, frame_center);
  FIELD(csc_merge_options, frame_scale);
  INIT(csc_merge_options, CSC_MERGE_OPTIONS_INIT, struct_size);
  INIT(csc_merge_options, CSC_MERGE_OPTIONS_INIT, method);
  INIT(csc_merge_options, CSC_MERGE_OPTIONS_INIT, use_frame);
  INIT(csc_merge_options, CSC_MERGE_OPTIONS_INIT, frame_scale);

  SIZE(csc_merge_timings);
  FIELD(csc_merge_timings, struct_size);
  FIELD(csc_merge_timings, isometry_ms);
  FIELD(csc_merge_timings, decompose_ms);
  FIELD(csc_merge_timings, blend_ms);
  FIELD(csc_merge_timings, apply_ms);
  INIT(csc_merge_timings, CSC_MERGE_TIMINGS_INIT, struct_size);

  SIZE(csc_session_options);
  FIELD(csc_session_options, struct_size);
  FIELD(csc_session_options, bind);
  FIELD(csc_session_options, name);
  FIELD(csc_session_options, id);
  FIELD(csc_session_options, sync_ms);
  FIELD(csc_session_options, heartbeat_ms);
  FIELD(csc_session_options, evasive_ms);
  FIELD(csc_session_options, expired_ms);
  FIELD(csc_session_options, position_tolerance);
  FIELD(csc_session_options, channel_tolerance);
  FIELD(csc_session_options, join_timeout_ms);
  FIELD(csc_session_options, journal_dir);
  INIT(csc_session_options, CSC_SESSION_OPTIONS_INIT, struct_size);
  INIT(csc_session_options, CSC_SESSION_OPTIONS_INIT, id);
  INIT(csc_session_options, CSC_SESSION_OPTIONS_INIT, sync_ms);
  INIT(csc_session_options, CSC_SESSION_OPTIONS_INIT, heartbeat_ms);
  INIT(csc_session_options, CSC_SESSION_OPTIONS_INIT, evasive_ms);
  INIT(csc_session_options, CSC_SESSION_OPTIONS_INIT, expired_ms);
  INIT(csc_session_options, CSC_SESSION_OPTIONS_INIT, position_tolerance);
  INIT(csc_session_options, CSC_SESSION_OPTIONS_INIT, channel_tolerance);
  INIT(csc_session_options, CSC_SESSION_OPTIONS_INIT, join_timeout_ms);

  SIZE(csc_session_event);
  FIELD(csc_session_event, struct_size);
  FIELD(csc_session_event, kind);
  FIELD(csc_session_event, peer);
  FIELD(csc_session_event, version);
  FIELD(csc_session_event, epoch);
  FIELD(csc_session_event, message);
  INIT(csc_session_event, CSC_SESSION_EVENT_INIT, struct_size);
  INIT(csc_session_event, CSC_SESSION_EVENT_INIT, kind);
  INIT(csc_session_event, CSC_SESSION_EVENT_INIT, peer);

  SIZE(csc_session_stats);
  FIELD(csc_session_stats, struct_size);
  FIELD(csc_session_stats, id);
  FIELD(csc_session_stats, version);
  FIELD(csc_session_stats, epoch);
  FIELD(csc_session_stats, merger);
  FIELD(csc_session_stats, members);
  FIELD(csc_session_stats, submits);
  FIELD(csc_session_stats, submit_bytes);
  FIELD(csc_session_stats, strokes_submitted);
  FIELD(csc_session_stats, strokes_acknowledged);
  FIELD(csc_session_stats, versions_applied);
  FIELD(csc_session_stats, rebases);
  FIELD(csc_session_stats, merges);
  FIELD(csc_session_stats, merged_strokes);
  FIELD(csc_session_stats, conflicting_strokes);
  FIELD(csc_session_stats, merge_ms_mean);
  FIELD(csc_session_stats, merge_ms_max);
  FIELD(csc_session_stats, messages_received);
  FIELD(csc_session_stats, messages_dropped);
  FIELD(csc_session_stats, stale_ignored);
  FIELD(csc_session_stats, auth_rejected);
  FIELD(csc_session_stats, folds_introduced);
  INIT(csc_session_stats, CSC_SESSION_STATS_INIT, struct_size);
  INIT(csc_session_stats, CSC_SESSION_STATS_INIT, members);
  INIT(csc_session_stats, CSC_SESSION_STATS_INIT, merge_ms_mean);
  INIT(csc_session_stats, CSC_SESSION_STATS_INIT, auth_rejected);

  SIZE(csc_presence);
  FIELD(csc_presence, struct_size);
  FIELD(csc_presence, peer);
  FIELD(csc_presence, position);
  FIELD(csc_presence, radius);
  FIELD(csc_presence, active);
  FIELD(csc_presence, visible);
  FIELD(csc_presence, rgba);
  FIELD(csc_presence, age_ms);
  FIELD(csc_presence, colour);
  INIT(csc_presence, CSC_PRESENCE_INIT, struct_size);
  INIT(csc_presence, CSC_PRESENCE_INIT, radius);
  INIT(csc_presence, CSC_PRESENCE_INIT, visible);

  SIZE(csc_peer_info);
  FIELD(csc_peer_info, struct_size);
  FIELD(csc_peer_info, id);
  FIELD(csc_peer_info, name);
  FIELD(csc_peer_info, state);
  FIELD(csc_peer_info, merger);
  FIELD(csc_peer_info, version);
  FIELD(csc_peer_info, latency_ms);
  INIT(csc_peer_info, CSC_PEER_INFO_INIT, struct_size);
  INIT(csc_peer_info, CSC_PEER_INFO_INIT, state);
  INIT(csc_peer_info, CSC_PEER_INFO_INIT, latency_ms);
  return 0;
}
