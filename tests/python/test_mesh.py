"""Mesh, Hierarchy and handle lifetimes through the Python binding: arrays in and out, files
(real and malformed ones from assimp-testmodels), views, closing, and the errors raised."""

import gc
import math
import os
import tempfile
import unittest
import weakref

import numpy as np

import meshes
import csculpt

MODELS = meshes.MODELS


def needs_models(test):
    return unittest.skipUnless(os.path.isdir(MODELS), f"{MODELS} (assimp-testmodels) missing")(test)


class MeshArrays(unittest.TestCase):

    def setUp(self):
        self.p, self.t = meshes.icosphere(2)
        n = len(self.p)
        self.albedo = np.random.default_rng(1).random((n, 3), dtype=np.float32)
        self.mask = np.linspace(0, 1, n, dtype=np.float32)

    def test_arrays_come_back_bit_identical(self):
        with csculpt.Mesh(self.p, self.t, {
                "albedo": (self.albedo, "srgb", (0.0, 1.0)),
                "mask": self.mask
        }) as m:
            self.assertEqual((m.vertex_count, m.triangle_count, m.channel_count),
                             (len(self.p), len(self.t), 2))
            self.assertEqual(m.positions.dtype, np.float32)
            self.assertEqual(m.triangles.dtype, np.uint32)
            np.testing.assert_array_equal(meshes.bits(m.positions), meshes.bits(self.p))
            np.testing.assert_array_equal(m.triangles, self.t)
            self.assertEqual(m.channel_names, ("albedo", "mask"))
            albedo = m.channels["albedo"]
            self.assertEqual((albedo.linearisation, albedo.range, albedo.width), ("srgb", (0.0, 1.0),
                                                                                  3))
            np.testing.assert_array_equal(meshes.bits(albedo.values), meshes.bits(self.albedo))
            mask = m.channel("mask")
            self.assertEqual((mask.linearisation, mask.range), ("identity", (-math.inf, math.inf)))
            np.testing.assert_array_equal(mask.values, self.mask)
            self.assertEqual(m.find_channel("mask"), 1)
            self.assertEqual(m.find_channel("nope"), -1)
            self.assertAlmostEqual(m.bbox_diagonal, 2 * math.sqrt(3), places=5)

    def test_the_library_copies_the_inputs(self):
        p = self.p.copy()
        with csculpt.Mesh(p, self.t) as m:
            p[:] = 7
            np.testing.assert_array_equal(m.positions, self.p)

    def test_other_dtypes_and_flat_arrays_are_converted(self):
        with csculpt.Mesh(self.p.astype(np.float64).ravel(), self.t.astype(np.int64),
                          {"c": csculpt.Channel(self.mask.astype(np.float64), "square",
                                                (0, 1))}) as m:
            np.testing.assert_array_equal(m.positions, self.p)
            np.testing.assert_array_equal(m.triangles, self.t)
            self.assertEqual(m.channel("c").linearisation, "square")

    def test_property_arrays_are_copies(self):
        with csculpt.Mesh(self.p, self.t) as m:
            a = m.positions
            a[:] = 0
            np.testing.assert_array_equal(m.positions, self.p)

    def test_add_material_channels(self):
        with csculpt.Mesh(self.p, self.t, {"mask": self.mask}) as m:
            m.add_material_channels()
            chans = m.channels
            self.assertEqual(list(chans), ["mask", "albedo", "metallic", "roughness"])
            self.assertEqual(chans["albedo"].linearisation, "srgb")
            self.assertEqual(chans["roughness"].linearisation, "square")
            np.testing.assert_array_equal(chans["albedo"].values, 0.5)
            np.testing.assert_array_equal(chans["metallic"].values, 0.0)
            np.testing.assert_array_equal(chans["roughness"].values, np.float32(0.7))
            np.testing.assert_array_equal(chans["mask"].values, self.mask)
            m.add_material_channels()  # adds only what is missing
            self.assertEqual(m.channel_count, 4)

    def test_invalid_meshes_raise_invalid_input_with_the_reason(self):
        bad = self.t.copy()
        bad[3, 1] = len(self.p)
        nan = self.p.copy()
        nan[5, 2] = np.nan
        cases = [
            ((self.p, bad), "out of range"),
            ((nan, self.t), ""),
            ((self.p[:0], self.t[:0]), ""),
            ((self.p, self.t, {"c": np.zeros((len(self.p), 5), np.float32)}), "width 5"),
            ((self.p, self.t, {"c": (self.mask, "identity", (1, 0))}), "min_value"),
            ((self.p, self.t, {"": self.mask}), "name"),
        ]
        for args, reason in cases:
            with self.subTest(reason=reason), self.assertRaises(csculpt.InvalidInput) as ctx:
                csculpt.Mesh(*args)
            self.assertEqual(ctx.exception.status, csculpt.Status.ERROR_INVALID_INPUT)
            self.assertIn("csc_mesh_create", str(ctx.exception))
            self.assertIn(reason, str(ctx.exception))

    def test_wrong_shapes_are_refused_before_the_library_reads_them(self):
        n = len(self.p)
        for args in [(self.p[:, :2], self.t), (self.p, self.t[:, :2]),
                     (self.p, self.t, {"c": np.zeros(n - 1, np.float32)}),
                     (self.p, self.t.astype(np.float32)),
                     (self.p, self.t, {"c": (self.mask, "gamma")})]:
            with self.assertRaises(csculpt.InvalidArgument):
                csculpt.Mesh(*args)

    def test_errors_are_value_errors_and_carry_status(self):
        with self.assertRaises(ValueError) as ctx:
            csculpt.Mesh(self.p, self.t[:, :2])
        self.assertIsInstance(ctx.exception, csculpt.CsculptError)
        self.assertEqual(ctx.exception.status, csculpt.Status.ERROR_INVALID_ARGUMENT)


class Files(unittest.TestCase):

    @needs_models
    def test_reads_a_real_ply_with_channels_and_writes_it_back_bit_identical(self):
        m = csculpt.Mesh.read(os.path.join(MODELS, "PLY", "Wuson.ply"))
        self.assertEqual((m.vertex_count, m.triangle_count), (11184, 3732))
        self.assertIn("nx", m.channel_names)
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "wuson.ply")
            m.write(path)
            again = csculpt.Mesh.read(path)
        np.testing.assert_array_equal(meshes.bits(again.positions), meshes.bits(m.positions))
        np.testing.assert_array_equal(again.triangles, m.triangles)
        self.assertEqual(again.channel_names, m.channel_names)
        for name, ch in m.channels.items():
            np.testing.assert_array_equal(meshes.bits(again.channel(name).values),
                                          meshes.bits(ch.values))

    @needs_models
    def test_reads_obj_off_stl(self):
        for path, counts in [("OBJ/box.obj", (8, 12)), ("OFF/Cube.off", (8, 12)),
                             ("STL/triangle.stl", (3, 1))]:
            with self.subTest(path=path), csculpt.Mesh.read(os.path.join(MODELS, path)) as m:
                self.assertEqual((m.vertex_count, m.triangle_count), counts)

    @needs_models
    def test_malformed_files_raise_invalid_input_naming_file_place_and_problem(self):
        path = os.path.join(MODELS, "invalid", "malformed.obj")
        with self.assertRaises(csculpt.InvalidInput) as ctx:
            csculpt.Mesh.read(path)
        self.assertEqual(str(ctx.exception),
                         f"csc_mesh_read: {path}:23: face index 12 out of range (8 vertices)")
        self.assertEqual(ctx.exception.message, str(ctx.exception))

    @needs_models
    def test_every_invalid_model_is_refused_with_a_message(self):
        folder = os.path.join(MODELS, "invalid")
        names = sorted(os.listdir(folder))
        self.assertGreaterEqual(len(names), 10)
        for name in names:
            path = os.path.join(folder, name)
            with self.subTest(file=name), self.assertRaises(csculpt.InvalidInput) as ctx:
                csculpt.Mesh.read(path)
            self.assertTrue(str(ctx.exception).startswith(f"csc_mesh_read: {path}:"),
                            str(ctx.exception))

    def test_missing_file_and_unwritable_path_raise_io_error(self):
        with self.assertRaises(csculpt.IoError) as ctx:
            csculpt.Mesh.read("/nonexistent/mesh.ply")
        self.assertIsInstance(ctx.exception, OSError)
        self.assertEqual(ctx.exception.status, csculpt.Status.ERROR_IO)
        self.assertIn("/nonexistent/mesh.ply", str(ctx.exception))
        p, t = meshes.icosphere(0)
        with csculpt.Mesh(p, t) as m, self.assertRaises(csculpt.IoError):
            m.write("/nonexistent/dir/mesh.ply")


class Hierarchies(unittest.TestCase):

    def test_stats_and_digest_are_a_function_of_the_triangles(self):
        p, t = meshes.icosphere(3)
        with csculpt.Mesh(p, t) as m, csculpt.Hierarchy(m) as h:
            s = h.stats
            self.assertEqual((s.vertices, s.faces, s.top_nodes), (len(p), len(t), 1))
            self.assertGreater(s.levels, 2)
            self.assertGreater(s.nodes, s.vertices)
            self.assertTrue(1.1 < s.node_ratio < 1.6, s.node_ratio)
            moved = csculpt.Mesh(p * 3 + 1, t)  # same connectivity, other positions
            with csculpt.Hierarchy(moved) as again:
                self.assertEqual(again.digest, h.digest)
            with csculpt.Hierarchy(m, max_parents=1) as tree:
                self.assertNotEqual(tree.digest, h.digest)

    @needs_models
    def test_a_real_mesh_of_many_components(self):
        with csculpt.Mesh.read(os.path.join(MODELS, "OFF", "Wuson.off")) as m:
            h = csculpt.Hierarchy(m)
            self.assertEqual(h.stats.top_nodes, 179)

    def test_out_of_range_max_parents_is_an_invalid_argument(self):
        p, t = meshes.icosphere(0)
        with csculpt.Mesh(p, t) as m:
            for k in (0, 33):
                with self.subTest(max_parents=k), self.assertRaises(csculpt.CsculptError) as ctx:
                    csculpt.Hierarchy(m, max_parents=k)
                self.assertIn("max_parents", str(ctx.exception))


class Lifetimes(unittest.TestCase):

    def setUp(self):
        self.p, self.t = meshes.icosphere(1)

    def test_close_releases_now_and_later_use_raises(self):
        m = csculpt.Mesh(self.p, self.t)
        owner = weakref.ref(m._owner)
        with m:
            pass
        self.assertTrue(m.closed)
        self.assertIsNone(owner(), "the C handle must be destroyed when the block ends")
        with self.assertRaisesRegex(csculpt.InvalidArgument, "mesh is closed"):
            m.vertex_count
        m.close()  # twice is harmless

    def test_garbage_collection_releases(self):
        m = csculpt.Mesh(self.p, self.t)
        owner = weakref.ref(m._owner)
        del m
        self.assertIsNone(owner())

    def test_a_view_keeps_the_memory_alive_after_close(self):
        m = csculpt.Mesh(self.p, self.t)
        view = m.positions_view()
        self.assertFalse(view.flags.writeable)
        with self.assertRaises(ValueError):
            view[0, 0] = 1
        m.close()
        del m
        gc.collect()
        np.testing.assert_array_equal(view, self.p)  # still readable (and ASan-clean)

    def test_views_follow_applied_diffs(self):
        with csculpt.Mesh(self.p, self.t) as m:
            view = m.positions_view()
            edited = self.p.copy()
            edited[0] += 1
            csculpt.Diff.capture(m, positions=edited).apply_to(m)
            np.testing.assert_array_equal(view, edited)

    def test_add_material_channels_is_refused_while_a_view_lives(self):
        with csculpt.Mesh(self.p, self.t, {"mask": np.zeros(len(self.p), np.float32)}) as m:
            view = m.channel("mask", copy=False)
            with self.assertRaisesRegex(csculpt.InvalidArgument, "view"):
                m.add_material_channels()
            self.assertEqual(m.channel_count, 1)
            del view
            m.add_material_channels()
            self.assertEqual(m.channel_count, 4)

    def test_clone_is_independent(self):
        with csculpt.Mesh(self.p, self.t) as m:
            c = m.clone()
            m.close()
            np.testing.assert_array_equal(c.positions, self.p)


if __name__ == "__main__":
    unittest.main()
