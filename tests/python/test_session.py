"""Sessions through the Python binding: two peers in one process on loopback, each editing its
own numpy arrays in place, converging bit for bit; events, statistics, attribution, leaving,
and the errors raised for bad invites, options and host arrays."""

import contextlib
import gc
import os
import tempfile
import time
import unittest
import weakref

import numpy as np

import meshes
import csculpt

# Short thresholds keep the test fast; the ordering heartbeat < evasive < expired is required.
FAST = dict(sync_ms=30, heartbeat_ms=50, evasive_ms=200, expired_ms=400)
# Generous: the ASan build runs the network threads several times slower.
DEADLINE_S = 30.0
NOBODY = "csculpt1:" + "0" * 144 + "@tcp://127.0.0.1:9"


def material_sphere(subdivisions=3):
    p, t = meshes.icosphere(subdivisions)
    mesh = csculpt.Mesh(p, t)
    mesh.add_material_channels()
    return mesh


def host_arrays(mesh):
    """The host's own arrays, as a DCC would keep them: copies, float32, C-contiguous."""
    return mesh.positions, {name: ch.values for name, ch in mesh.channels.items()}


def same_bits(pa, ca, pb, cb):
    return (np.array_equal(meshes.bits(pa), meshes.bits(pb)) and ca.keys() == cb.keys() and
            all(np.array_equal(meshes.bits(ca[k]), meshes.bits(cb[k])) for k in ca))


@contextlib.contextmanager
def two_artists(subdivisions=4):
    """A session of two artists on a material sphere: (mesh, the base positions, hosts), hosts
    as synced() takes them, each host's arrays its own copies of the base."""
    with material_sphere(subdivisions) as mesh, csculpt.Session.create(mesh, id=1, **FAST) as a, \
            csculpt.Session.join(a.invite, id=2, join_timeout_ms=10000, **FAST) as b:
        base_p, _ = host_arrays(mesh)
        pa, ca = host_arrays(mesh)
        with b.base() as b_base:
            pb, cb = host_arrays(b_base)
        yield mesh, base_p, {"a": (a, pa, ca), "b": (b, pb, cb)}


def synced(hosts, pending, strokes):
    """One round of two artists' hosts ("a" and "b": session, positions, channels): each
    updates and submits its pending strokes. True once both hold the same version, bit for bit,
    and a has `strokes` acknowledged."""
    for key, (session, p, c) in hosts.items():
        session.update(p, c)
        if session.submit(p, c, strokes=pending[key]):
            pending[key] = 0
    (a, pa, ca), (b, pb, cb) = hosts["a"], hosts["b"]
    return (a.version == b.version and a.stats.strokes_acknowledged == strokes and
            same_bits(pa, ca, pb, cb))


def wait_for(condition, what, deadline_s=DEADLINE_S):
    end = time.monotonic() + deadline_s
    while not condition():
        if time.monotonic() > end:
            raise AssertionError(f"timed out after {deadline_s} s waiting for {what}")
        time.sleep(0.005)


class TwoPeers(unittest.TestCase):

    def test_two_hosts_edit_their_arrays_in_place_and_converge(self):
        with material_sphere() as mesh, csculpt.Session.create(mesh, id=1, name="a", **FAST) as a:
            self.assertTrue(a.invite.startswith("csculpt1:"), a.invite)
            self.assertEqual((a.id, a.version), (1, 0))
            with csculpt.Session.join(a.invite, id=2, name="b", join_timeout_ms=10000,
                                      **FAST) as b:
                self.run_two_peers(mesh, a, b)

    def run_two_peers(self, mesh, a, b):
        self.assertEqual(b.id, 2)
        self.assertEqual(b.channel_names, ("albedo", "metallic", "roughness"))
        base_p, base_c = host_arrays(mesh)
        with b.base() as b_base:
            pb, cb = host_arrays(b_base)
        self.assertTrue(same_bits(base_p, base_c, pb, cb), "the snapshot differs from the mesh")
        pa, ca = host_arrays(mesh)

        # a grabs the north cap upwards; b paints the south cap red: disjoint regions.
        pa[:] = meshes.grab(pa, (0, 0, 1), 0.6, (0, 0, 0.3))
        a_region = np.any(pa != base_p, axis=1)
        b_region = base_p[:, 2] < -0.6
        cb["albedo"][b_region] = (1.0, 0.0, 0.0)
        untouched = ~a_region & ~b_region
        self.assertGreater(a_region.sum(), 20)
        self.assertGreater(b_region.sum(), 20)
        self.assertFalse((a_region & b_region).any())

        # submit rewrites the host's changed values in place to what the peers receive.
        edited = pa.copy()
        pa_buffer = pa.ctypes.data
        self.assertTrue(a.submit(pa, ca, strokes=1))
        self.assertEqual(pa.ctypes.data, pa_buffer)
        self.assertFalse(np.array_equal(meshes.bits(pa), meshes.bits(edited)),
                         "no value was rewritten to its wire quantisation")
        tolerance = csculpt.SESSION_OPTIONS["position_tolerance"] * mesh.bbox_diagonal
        np.testing.assert_allclose(pa, edited, rtol=0, atol=tolerance)
        self.assertFalse(a.submit(pa, ca), "a second submit of the same edit sent again")
        pending = {"a": 0, "b": 1}

        events = {"a": [], "b": []}
        hosts = {"a": (a, pa, ca), "b": (b, pb, cb)}

        def step():
            for key, (session, p, c) in hosts.items():
                session.update(p, c)
                if session.submit(p, c, strokes=pending[key]):
                    pending[key] = 0
                events[key] += session.events()
            sa, sb = a.stats, b.stats
            return (a.version == b.version >= 1 and sa.strokes_acknowledged == 1 and
                    sb.strokes_acknowledged == 1 and same_bits(pa, ca, pb, cb))

        wait_for(step, "both peers at the same version with identical arrays")
        self.assertEqual(pending, {"a": 0, "b": 0})

        # Both edits are on both hosts; what nobody touched kept its exact base values.
        for p, c in ((pa, ca), (pb, cb)):
            self.assertGreater(float((p[:, 2] - base_p[:, 2]).max()), 0.2)
            self.assertGreater(float(c["albedo"][b_region, 0].min()), 0.99)
            self.assertLess(float(c["albedo"][b_region, 1].max()), 0.01)
            np.testing.assert_array_equal(meshes.bits(p[untouched]),
                                          meshes.bits(base_p[untouched]))
            np.testing.assert_array_equal(meshes.bits(p[b_region]), meshes.bits(base_p[b_region]))
            for name in ("metallic", "roughness"):
                np.testing.assert_array_equal(meshes.bits(c[name]), meshes.bits(base_c[name]))
        with a.base() as agreed:
            self.assertTrue(same_bits(pa, ca, *host_arrays(agreed)),
                            "the host's arrays differ from the agreed version")

        for key in ("a", "b"):
            kinds = {e.kind for e in events[key]}
            with self.subTest(peer=key):
                self.assertIn(csculpt.EventKind.JOINED, kinds)
                self.assertIn(csculpt.EventKind.VERSION, kinds)
                for e in events[key]:
                    self.assertIsInstance(e.message, str)
                    self.assertIsInstance(e.kind, csculpt.EventKind)
        versions = [e.version for e in events["a"] if e.kind == csculpt.EventKind.VERSION]
        self.assertEqual(versions, sorted(versions))
        self.assertEqual(versions[-1], a.version)

        sa, sb = a.stats, b.stats
        self.assertEqual((sa.id, sb.id), (1, 2))
        self.assertEqual((sa.merger, sb.merger), (1, 1))  # the lowest live id merges
        self.assertGreaterEqual(sa.merges, 1)
        self.assertEqual(sb.merges, 0)
        self.assertEqual((sa.strokes_submitted, sb.strokes_submitted), (1, 1))
        self.assertEqual(sa.merged_strokes, 2)
        self.assertEqual((sa.members, sb.members), (2, 2))
        self.assertGreaterEqual(sb.versions_applied, 1)
        self.assertGreater(sa.submit_bytes, 0)
        self.assertEqual((sa.messages_dropped, sb.messages_dropped), (0, 0))
        self.assertEqual((sa.auth_rejected, sb.auth_rejected), (0, 0))
        self.assertGreater(sa.merge_ms_max, 0.0)
        self.assertLessEqual(sa.merge_ms_mean, sa.merge_ms_max)

        for session in (a, b):
            rgb = session.attribution_colors()
            with self.subTest(peer=session.id):
                self.assertEqual((rgb.shape, rgb.dtype), ((len(base_p), 3), np.float32))
                self.assertTrue(((rgb >= 0) & (rgb <= 1)).all())
                a_colour, b_colour = rgb[a_region].mean(axis=0), rgb[b_region].mean(axis=0)
                self.assertGreater(float(np.abs(a_colour - b_colour).max()), 0.3)
                # The header's palette by increasing id: green for a (1), blue for b (2).
                self.assertGreater(a_colour[1], a_colour[2])
                self.assertGreater(b_colour[2], b_colour[1])
                np.testing.assert_allclose(rgb[untouched], 0.82, atol=1e-6)

        b.leave()
        with self.assertRaises(csculpt.InvalidArgument):
            b.submit(pb, cb, strokes=1)
        with self.assertRaises(csculpt.InvalidArgument):
            b.update(pb, cb)
        with self.assertRaises(csculpt.InvalidArgument):
            b.leave()
        self.assertEqual((b.id, b.version), (2, a.version))  # reads still work
        self.assertEqual(b.stats.id, 2)
        self.assertIsInstance(b.events(), list)
        with b.base() as left_base:
            self.assertTrue(same_bits(pb, cb, *host_arrays(left_base)))

        def a_saw_b_leave():
            events["a"] += a.events()
            return any(e.kind == csculpt.EventKind.PEER_LEFT and e.peer == 2 for e in events["a"])

        wait_for(a_saw_b_leave, "a PEER_LEFT event for b on a")
        wait_for(lambda: a.stats.members == 1, "a to count 1 member")


class Journal(unittest.TestCase):

    def test_resume_gives_back_the_session_and_the_unmerged_edit(self):
        with tempfile.TemporaryDirectory() as tmp:
            journal = os.path.join(tmp, "journal")
            slow = dict(FAST, sync_ms=3000)  # the first merge 3 s after the start
            with material_sphere() as mesh, \
                    csculpt.Session.create(mesh, id=4, journal_dir=journal, **slow) as a:
                invite = a.invite
                pa, ca = host_arrays(mesh)
                pa[:] = meshes.grab(pa, (0, 0, 1), 0.6, (0, 0, 0.3))
                self.assertTrue(a.submit(pa, ca, strokes=1))
                wait_for(lambda: a.stats.submits > 0, "the submit (journaled first)")
            with self.assertRaises(csculpt.IoError):
                csculpt.Session.resume(os.path.join(tmp, "nothing"))
            b, local = csculpt.Session.resume(journal, **slow)
            with b, local:
                self.assertEqual((b.id, b.version, b.invite), (4, 0, invite))
                pb, cb = host_arrays(local)
                self.assertTrue(same_bits(pa, ca, pb, cb), "the unmerged edit is not back")


class Undo(unittest.TestCase):

    def test_undo_takes_back_my_stroke_on_both_peers_and_keeps_theirs(self):
        with two_artists() as (mesh, base_p, hosts):
            (a, pa, ca), (b, pb, cb) = hosts["a"], hosts["b"]
            stride = 3 + 3 + 1 + 1
            # a grabs the north cap sideways and records it for undo ...
            before = np.concatenate([pa] + [c.reshape(len(pa), -1) for c in ca.values()], axis=1)
            pa[:] = meshes.grab(pa, (0, 0, 1), 0.7, (0.25, 0, 0))
            mine = np.flatnonzero(np.any(pa != base_p, axis=1))
            a.record_stroke(pa, mine, before[mine], ca)
            self.assertEqual(a.undo_depth, (1, 0))
            # ... b grabs a band overlapping it upwards.
            pb[:] = meshes.grab(pb, (0.6, 0, 0.8), 0.6, (0, 0, 0.2))
            theirs = np.any(pb != base_p, axis=1)
            pending = {"a": 1, "b": 1}

            wait_for(lambda: synced(hosts, pending, 1) and b.stats.strokes_acknowledged == 1,
                     "both strokes")
            both = pa.copy()
            changed = a.undo(pa, ca)
            self.assertGreater(changed.size, 0)
            self.assertEqual(a.undo_depth, (0, 1))
            pending["a"] = 1
            wait_for(lambda: synced(hosts, pending, 2), "the undo on both peers")
            tolerance = 4 * csculpt.SESSION_OPTIONS["position_tolerance"] * mesh.bbox_diagonal
            only_mine = np.zeros(len(pa), bool)
            only_mine[mine] = True
            # Vertices sharing a face with b's edit turn with it (the merge carries my removal in
            # b's frame there): "alone" means away from those faces.
            triangles = np.asarray(mesh.triangles).reshape(-1, 3)
            near_theirs = theirs.copy()
            near_theirs[triangles[theirs[triangles].any(axis=1)].ravel()] = True
            only_mine &= ~near_theirs
            self.assertGreater(only_mine.sum(), 10)
            for p in (pa, pb):  # my stroke is gone where it was alone, on both peers ...
                np.testing.assert_allclose(p[only_mine], base_p[only_mine], rtol=0, atol=tolerance)
                # ... and b's upward grab stays, also where the two overlapped.
                lifted = p[theirs, 2] - base_p[theirs, 2]
                self.assertGreater(float(lifted.max()), 0.15)
            self.assertGreater(float(np.abs(both - pa).max()), 0.1)
            self.assertGreater(a.redo(pa, ca).size, 0)
            self.assertEqual(a.undo_depth, (1, 0))
            np.testing.assert_allclose(pa[only_mine], both[only_mine], rtol=0, atol=0.02)
            self.assertGreater(a.undo(pa, ca).size, 0)
            self.assertEqual(b.undo(pb, cb).size, 0, "b has no stroke of its own to undo")

            with self.assertRaises(csculpt.InvalidInput):
                a.record_stroke(pa, [0, 0], np.zeros((2, stride)), ca)  # a vertex twice
            with self.assertRaises(csculpt.InvalidInput):
                a.record_stroke(pa, [len(pa)], np.zeros((1, stride)), ca)
            with self.assertRaises(csculpt.InvalidArgument):
                a.record_stroke(pa, [1, 2], np.zeros((1, stride)), ca)  # too few values
            self.assertEqual(a.undo_depth, (0, 1), "a refused stroke changed the history")

    def test_undoing_a_broad_stroke_stands_a_detail_made_on_it_upright_again(self):
        # a drags the whole north cap sideways; b raises a small bump on the slope it made. When
        # a takes the drag back, the bump goes back with the surface it was made on: upright on
        # the sphere, as tall as b made it, and nothing else of a's drag stays.
        with two_artists() as (_, base_p, hosts):
            (a, pa, ca), (b, pb, cb) = hosts["a"], hosts["b"]
            before = np.concatenate([pa] + [c.reshape(len(pa), -1) for c in ca.values()], axis=1)
            pa[:] = meshes.grab(pa, (0, 0, 1), 0.9, (0.35, 0, 0))
            mine = np.flatnonzero(np.any(pa != base_p, axis=1))
            a.record_stroke(pa, mine, before[mine], ca)
            top = np.array([0.3, 0, 0.954], np.float32)
            top /= np.linalg.norm(top)
            pb[:] = meshes.grab(pb, top, 0.2, 0.06 * top)
            theirs = np.flatnonzero(np.any(pb != base_p, axis=1))
            self.assertGreater(len(mine), 4 * len(theirs))
            pending = {"a": 1, "b": 1}

            wait_for(lambda: synced(hosts, pending, 1) and b.stats.strokes_acknowledged == 1,
                     "both strokes")
            self.assertGreater(a.undo(pa, ca).size, 0)
            pending["a"] = 1
            wait_for(lambda: synced(hosts, pending, 2), "the undo on both peers")
            alone = np.setdiff1d(mine, theirs)
            far = alone[np.linalg.norm(base_p[alone] - top, axis=1) > 0.35]
            self.assertGreater(len(far), 100)
            for p in (pa, pb):
                lift = p[theirs] - base_p[theirs]
                peak = int(np.argmax(np.linalg.norm(lift, axis=1)))
                self.assertGreater(float(np.linalg.norm(lift[peak])), 0.8 * 0.06, "the bump shrank")
                tilt = np.degrees(np.arccos(np.dot(lift[peak], top) / np.linalg.norm(lift[peak])))
                self.assertLess(float(tilt), 8.0, "the bump kept the undone drag's slope")
                np.testing.assert_allclose(p[far], base_p[far], rtol=0, atol=0.002)


class PresenceAndPeers(unittest.TestCase):

    def test_cursors_and_peer_info_cross_the_binding(self):
        with material_sphere() as mesh, \
                csculpt.Session.create(mesh, id=1, name="ana", **FAST) as a, \
                csculpt.Session.join(a.invite, id=2, name="ben", join_timeout_ms=10000,
                                     **FAST) as b:
            a.set_presence((0.25, 0.5, -1.0), 0.125, active=True)
            wait_for(lambda: b.presence(), "a's cursor at b")
            [p] = b.presence()
            self.assertEqual((p.peer, p.position, p.radius, p.active, p.visible),
                             (1, (0.25, 0.5, -1.0), 0.125, True, True))
            self.assertLess(p.age_ms, 1000)
            self.assertEqual(len(p.colour), 3)
            wait_for(lambda: b.peers() and b.peers()[0].latency_ms > 0, "a round trip")
            [info] = b.peers()
            self.assertEqual((info.id, info.name, info.state, info.merger),
                             (1, "ana", csculpt.PeerState.LIVE, True))
            self.assertLess(info.latency_ms, 1000.0)
            with self.assertRaisesRegex(csculpt.InvalidArgument, "radius is negative"):
                a.set_presence((0, 0, 0), -1.0)
            with self.assertRaisesRegex(csculpt.InvalidArgument, "position.x"):
                a.set_presence((float("nan"), 0, 0), 1.0)
            b.leave()
            wait_for(lambda: not a.presence() and a.peers() and
                     a.peers()[0].state == csculpt.PeerState.LEFT, "b gone from a's view")
            self.assertEqual(csculpt.EventKind.PEER_LIVE, 8)

class Errors(unittest.TestCase):

    def test_a_malformed_invite_is_invalid_input(self):
        for invite in ["not an invite", "csculpt1:" + "0" * 144, "csculpt1:00@tcp://127.0.0.1:9",
                       "csculpt1:" + "z" * 144 + "@tcp://127.0.0.1:9", ""]:
            with self.subTest(invite=invite), self.assertRaises(csculpt.InvalidInput) as ctx:
                csculpt.Session.join(invite, join_timeout_ms=300)
            self.assertTrue(str(ctx.exception))
        with self.assertRaisesRegex(csculpt.InvalidInput, "csculpt1:"):
            csculpt.Session.join("not an invite")
        with self.assertRaises(csculpt.InvalidArgument):
            csculpt.Session.join(b"csculpt1:")

    def test_joining_nobody_is_an_io_error_after_the_timeout(self):
        start = time.monotonic()
        with self.assertRaises(csculpt.IoError):
            csculpt.Session.join(NOBODY, join_timeout_ms=300, **FAST)
        elapsed = time.monotonic() - start
        self.assertGreaterEqual(elapsed, 0.25)
        self.assertLess(elapsed, 10.0)

    def test_options_are_checked(self):
        with material_sphere(1) as mesh:
            with self.assertRaisesRegex(TypeError, "sync"):
                csculpt.Session.create(mesh, sync=30)
            for bad in [dict(id=-1), dict(id=2**64), dict(sync_ms=2**32), dict(sync_ms=1.5),
                        dict(heartbeat_ms=True), dict(name=b"bytes")]:
                with self.subTest(**{k: repr(v) for k, v in bad.items()}):
                    with self.assertRaises(csculpt.InvalidArgument):
                        csculpt.Session.create(mesh, **bad)
            # The library's own checks come through with its message.
            with self.assertRaisesRegex(csculpt.InvalidArgument, "evasive"):
                csculpt.Session.create(mesh, evasive_ms=600, expired_ms=600)
            with self.assertRaisesRegex(csculpt.InvalidArgument, "tolerance"):
                csculpt.Session.create(mesh, position_tolerance=-1.0)
            with self.assertRaisesRegex(csculpt.IoError, "256.1.1.1"):
                csculpt.Session.create(mesh, bind="tcp://256.1.1.1:1")

    def test_host_arrays_must_be_writable_in_place(self):
        with material_sphere(1) as mesh, csculpt.Session.create(mesh, **FAST) as s:
            p, c = host_arrays(mesh)
            self.assertFalse(s.submit(p, c))  # nothing edited
            self.assertEqual(s.update(p, c), 0)
            bad_positions = [p.astype(np.float64), np.asfortranarray(p.reshape(3, -1)),
                             p[::2], p.tolist(), None, p[:-1]]
            readonly = p.copy()
            readonly.flags.writeable = False
            bad_positions.append(readonly)
            for bad in bad_positions:
                with self.subTest(positions=type(bad).__name__):
                    with self.assertRaises(csculpt.InvalidArgument):
                        s.submit(bad, c, strokes=1)
                    with self.assertRaises(csculpt.InvalidArgument):
                        s.update(bad, c)
            with self.assertRaises(csculpt.InvalidArgument):
                s.submit(p, {"albedo": c["albedo"].astype(np.float64)})
            with self.assertRaises(csculpt.InvalidArgument):
                s.submit(p, {"colour": c["albedo"]})
            with self.assertRaises(csculpt.InvalidArgument):
                s.submit(p, [c["albedo"]])  # a sequence must name every channel
            for strokes in (-1, 2**32):
                with self.assertRaises(csculpt.InvalidArgument):
                    s.submit(p, c, strokes=strokes)
            # Flat positions and a sequence with None entries are fine.
            self.assertFalse(s.submit(p.reshape(-1), [c["albedo"], None, None]))
            # Bad values are refused before anything is sent or written back.
            p[3, 1] = np.nan
            with self.assertRaises(csculpt.InvalidInput):
                s.submit(p, c, strokes=1)
            self.assertTrue(np.isnan(p[3, 1]))
            self.assertEqual(s.stats.submits, 0)

    def test_attribution_before_any_edit_is_grey(self):
        with material_sphere(1) as mesh, csculpt.Session.create(mesh, **FAST) as s:
            rgb = s.attribution_colors()
            self.assertEqual(rgb.shape, (mesh.vertex_count, 3))
            np.testing.assert_allclose(rgb, 0.82, atol=1e-6)


class Lifetime(unittest.TestCase):

    def test_a_lone_session_merges_its_own_edit(self):
        with material_sphere(1) as mesh, csculpt.Session.create(mesh, id=7, **FAST) as s:
            p, c = host_arrays(mesh)
            p[:] = meshes.grab(p, (1, 0, 0), 0.8, (0.2, 0, 0))
            self.assertTrue(s.submit(p, c, strokes=1))
            expected = p.copy()  # as quantised by submit
            wait_for(lambda: s.update(p, c) > 0 or s.version >= 1, "version 1")
            self.assertEqual(s.version, 1)
            np.testing.assert_array_equal(meshes.bits(p), meshes.bits(expected))
            with s.base() as agreed:
                np.testing.assert_array_equal(meshes.bits(agreed.positions), meshes.bits(p))
            self.assertEqual(s.stats.strokes_acknowledged, 1)

    def test_a_submit_of_the_changed_vertices_sends_them_and_refuses_a_bad_index(self):
        with material_sphere(2) as mesh, csculpt.Session.create(mesh, id=7, **FAST) as s:
            p, c = host_arrays(mesh)
            base_p = p.copy()
            p[:] = meshes.grab(p, (1, 0, 0), 0.8, (0.2, 0, 0))
            changed = np.flatnonzero(np.any(p != base_p, axis=1))
            self.assertGreater(changed.size, 5)
            before = p.copy()
            with self.assertRaisesRegex(csculpt.InvalidInput, f"changed vertex {len(p) + 3}"):
                s.submit_changed(p, list(changed) + [len(p) + 3], c, strokes=1)
            np.testing.assert_array_equal(meshes.bits(p), meshes.bits(before))  # not written
            # Unsorted, with repeats; the values are rewritten to what the peers receive.
            self.assertTrue(s.submit_changed(p, np.concatenate([changed[::-1], changed]), c,
                                             strokes=1))
            self.assertFalse(np.array_equal(meshes.bits(p), meshes.bits(before)))
            self.assertFalse(s.submit_changed(p, [], c))  # nothing new
            expected = p.copy()
            wait_for(lambda: s.update_changed(p, [], c) > 0 or s.version >= 1, "version 1")
            with s.base() as agreed:
                np.testing.assert_array_equal(meshes.bits(agreed.positions), meshes.bits(expected))
            self.assertEqual(s.stats.strokes_submitted, 1)
            with self.assertRaisesRegex(csculpt.InvalidInput, f"changed vertex {len(p)}"):
                s.update_changed(p, [len(p)], c)

    def test_close_context_manager_and_garbage_collection(self):
        with material_sphere(1) as mesh:
            p, c = host_arrays(mesh)
            closed = csculpt.Session.create(mesh, **FAST)
            invite = closed.invite
            closed.close()
            self.assertTrue(closed.closed)
            closed.close()  # harmless
            for use in (lambda: closed.id, lambda: closed.invite, lambda: closed.events(),
                        lambda: closed.stats, lambda: closed.base(), lambda: closed.leave(),
                        lambda: closed.attribution_colors(), lambda: closed.submit(p, c),
                        lambda: closed.update(p, c)):
                with self.assertRaisesRegex(csculpt.InvalidArgument, "closed"):
                    use()
            # Its network thread is gone: nobody answers that invite any more.
            with self.assertRaises(csculpt.IoError):
                csculpt.Session.join(invite, join_timeout_ms=300, **FAST)

            with csculpt.Session.create(mesh, **FAST) as managed:
                self.assertFalse(managed.closed)
            self.assertTrue(managed.closed)

            collected = csculpt.Session.create(mesh, **FAST)
            invite = collected.invite
            owner = weakref.ref(collected._owner)
            del collected
            gc.collect()
            self.assertIsNone(owner())
            with self.assertRaises(csculpt.IoError):
                csculpt.Session.join(invite, join_timeout_ms=300, **FAST)

    def test_construct_only_through_create_or_join(self):
        with self.assertRaises(TypeError):
            csculpt.Session()


if __name__ == "__main__":
    unittest.main()
