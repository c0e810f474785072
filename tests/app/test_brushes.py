"""Every brush and paint channel, replayed through csculpt-app's input handlers on the
built-in sphere (unit radius, centred, seen from the front: window pixel (640, 400) is the
sphere's front pole). Each test saves the mesh and asserts what the brush must have done."""
import os
import sys
import unittest

sys.path.insert(0, os.path.dirname(__file__))
from applib import (TEST_SPHERE, Mesh, Replay, assert_normals_current, changed_in, mean,  # noqa: E402
                    moved_vertices, run_app, temp_dir)

ACROSS = ((590, 400), (690, 400))  # a horizontal stroke through the front pole


class Brushes(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        import tempfile
        cls.dir = tempfile.TemporaryDirectory(prefix="csculpt-app-brushes-")
        cls.base_path = os.path.join(cls.dir.name, "base.ply")
        run_app(*TEST_SPHERE, "--exit-after", "0", "--save", cls.base_path)
        cls.base = Mesh(cls.base_path)

    @classmethod
    def tearDownClass(cls):
        cls.dir.cleanup()

    def sculpt(self, replay):
        directory = temp_dir(self)
        saved = os.path.join(directory, "out.ply")
        result = run_app(*TEST_SPHERE, "--replay", replay.write(directory), "--exit-after", "0",
                         "--save", saved)
        assert_normals_current(self, result.stdout)  # every brush keeps its normals exact
        return Mesh(saved)

    def radial_change(self, after, vertices):
        return mean(after.radius(v) - self.base.radius(v) for v in vertices)

    def test_sphere_is_a_unit_sphere_with_material_channels(self):
        self.assertGreater(self.base.face_count, 15000)
        for name in ("albedo_r", "albedo_g", "albedo_b", "metallic", "roughness"):
            self.assertIn(name, self.base.properties)
        self.assertAlmostEqual(max(self.base.radius(v) for v in range(self.base.vertex_count)), 1.0, places=5)

    def test_draw_raises_and_ctrl_carves(self):
        raised = self.sculpt(Replay().key("d").drag(*ACROSS))
        moved = moved_vertices(self.base, raised)
        self.assertGreater(len(moved), 50)
        self.assertGreater(self.radial_change(raised, moved), 0.005)
        carved = self.sculpt(Replay().key("d").drag(*ACROSS, mods=("ctrl",)))
        self.assertLess(self.radial_change(carved, moved_vertices(self.base, carved)), -0.005)

    def test_inflate_and_deflate(self):
        inflated = self.sculpt(Replay().key("i").drag(*ACROSS))
        moved = moved_vertices(self.base, inflated)
        self.assertGreater(len(moved), 50)
        self.assertGreater(self.radial_change(inflated, moved), 0.005)
        deflated = self.sculpt(Replay().key("i").drag(*ACROSS, mods=("ctrl",)))
        self.assertLess(self.radial_change(deflated, moved_vertices(self.base, deflated)), -0.005)

    def test_shift_smooths_a_drawn_ridge_down(self):
        ridge = self.sculpt(Replay().key("d").drag(*ACROSS))
        smoothed = self.sculpt(Replay().key("d").drag(*ACROSS).drag(*ACROSS, mods=("shift",)))
        moved = moved_vertices(self.base, ridge)
        peak = max(ridge.radius(v) for v in moved)
        self.assertLess(max(smoothed.radius(v) for v in moved), peak - 0.002)
        self.assertNotEqual(moved_vertices(ridge, smoothed), [])

    def test_flatten_cuts_the_cap_towards_its_plane(self):
        flat = self.sculpt(Replay().key("l").key("=").key("=").drag(*ACROSS))
        moved = moved_vertices(self.base, flat)
        self.assertGreater(len(moved), 50)
        # Towards the plane through the dab's centre: the crest along the stroke comes down,
        # the rim beside it comes up (neither draw, inflate nor crease does both).
        crest = [v for v in moved if abs(self.base.position(v)[1]) < 0.03]
        self.assertLess(mean(flat.radius(v) for v in crest), 1.0 - 0.0005)
        self.assertGreater(max(flat.radius(v) for v in moved), 1.0 + 0.0002)

    def test_crease_cuts_a_groove(self):
        crease = self.sculpt(Replay().key("c").drag(*ACROSS))
        moved = moved_vertices(self.base, crease)
        self.assertGreater(len(moved), 50)
        self.assertLess(self.radial_change(crease, moved), -0.002)

    def test_pinch_pulls_towards_the_stroke(self):
        pinched = self.sculpt(Replay().key("p").drag(*ACROSS))
        moved = [v for v in moved_vertices(self.base, pinched) if abs(self.base.position(v)[1]) > 0.02]
        self.assertGreater(len(moved), 20)
        self.assertLess(mean(abs(pinched.position(v)[1]) for v in moved),
                        mean(abs(self.base.position(v)[1]) for v in moved) - 0.002)

    def test_twist_turns_the_surface_about_its_normal(self):
        twisted = self.sculpt(Replay().key("t").key("x").drag((640, 400), (660, 400), steps=8))
        moved = moved_vertices(self.base, twisted)
        self.assertGreater(len(moved), 20)
        along = mean(sum((a - b) ** 2 for a, b in zip(twisted.position(v), self.base.position(v))) ** 0.5
                     for v in moved)
        radial = mean(abs(twisted.radius(v) - self.base.radius(v)) for v in moved)
        self.assertGreater(along, 0.002)
        self.assertLess(radial, 0.3 * along)  # a turn in the tangent plane, not a push
        # Above the pole the surface turns one way, below it the other.
        above = mean(twisted.position(v)[0] - self.base.position(v)[0] for v in moved if self.base.position(v)[1] > 0.02)
        below = mean(twisted.position(v)[0] - self.base.position(v)[0] for v in moved if self.base.position(v)[1] < -0.02)
        self.assertLess(above * below, 0.0)

    def test_grab_follows_the_cursor(self):
        grabbed = self.sculpt(Replay().key("g").key("x").drag((640, 400), (740, 400), steps=10))
        moved = moved_vertices(self.base, grabbed)
        self.assertGreater(len(moved), 20)
        dx = [grabbed.position(v)[0] - self.base.position(v)[0] for v in moved]
        dy = [grabbed.position(v)[1] - self.base.position(v)[1] for v in moved]
        self.assertGreater(max(dx), 0.2)  # 100 px is about 0.36 at the pole
        self.assertGreater(min(dx), -1e-6)  # nothing moves against the cursor (symmetry off)
        self.assertLess(abs(mean(dy)), 0.1 * mean(dx))

    def test_a_draw_after_a_grab_over_the_same_spot_raises_it(self):
        # The grab's region query and the draw's share the sculptor's list of leaves met and
        # its marks: the draw must still
        # recompute every normal around what it moved and refit the boxes it crossed.
        grab_then_draw = Replay().key("x").key("g").drag((640, 400), (660, 400), steps=4)
        both = self.sculpt(grab_then_draw.key("d").drag(*ACROSS).drag(*ACROSS))
        grabbed = self.sculpt(Replay().key("x").key("g").drag((640, 400), (660, 400), steps=4))
        raised = [v for v in moved_vertices(grabbed, both)]
        self.assertGreater(len(raised), 50)
        self.assertGreater(mean(both.radius(v) - grabbed.radius(v) for v in raised), 0.005)

    def test_x_symmetry_mirrors_and_can_be_turned_off(self):
        right_only = ((700, 380), (740, 380))
        mirrored = self.sculpt(Replay().key("d").drag(*right_only))
        moved = moved_vertices(self.base, mirrored)
        left = [v for v in moved if self.base.position(v)[0] < -0.1]
        right = [v for v in moved if self.base.position(v)[0] > 0.1]
        self.assertGreater(len(right), 20)
        self.assertGreater(len(left), 0.7 * len(right))
        single = self.sculpt(Replay().key("d").key("x").drag(*right_only))
        self.assertEqual([v for v in moved_vertices(self.base, single) if self.base.position(v)[0] < -0.05], [])

    def test_y_symmetry_mirrors_across_y(self):
        below_only = ((700, 470), (740, 470))
        mirrored = self.sculpt(Replay().key("d").key("x").key("y").drag(*below_only))
        moved = moved_vertices(self.base, mirrored)
        self.assertGreater(len([v for v in moved if self.base.position(v)[1] > 0.1]), 10)
        self.assertEqual([v for v in moved if self.base.position(v)[0] < -0.05], [])

    def test_paint_albedo_changes_colour_not_shape(self):
        painted = self.sculpt(Replay().key("b").drag(*ACROSS))
        self.assertEqual(moved_vertices(self.base, painted), [])
        changed = changed_in(self.base, painted, "albedo_r")
        self.assertGreater(len(changed), 50)
        self.assertGreater(mean(painted.columns["albedo_r"][v] - self.base.columns["albedo_r"][v] for v in changed), 0.05)
        self.assertLess(mean(painted.columns["albedo_g"][v] - self.base.columns["albedo_g"][v] for v in changed), -0.05)
        self.assertEqual(changed_in(self.base, painted, "roughness"), [])

    def test_paint_roughness(self):
        painted = self.sculpt(Replay().key("r").drag(*ACROSS))
        changed = changed_in(self.base, painted, "roughness")
        self.assertGreater(len(changed), 50)
        target = 0.15
        self.assertLess(mean(abs(painted.columns["roughness"][v] - target) for v in changed),
                        mean(abs(self.base.columns["roughness"][v] - target) for v in changed) - 0.05)
        self.assertEqual(changed_in(self.base, painted, "albedo_r"), [])
        self.assertEqual(moved_vertices(self.base, painted), [])

    def test_paint_metallic(self):
        painted = self.sculpt(Replay().key("m").drag(*ACROSS))
        changed = changed_in(self.base, painted, "metallic")
        self.assertGreater(len(changed), 50)
        self.assertGreater(mean(painted.columns["metallic"][v] - self.base.columns["metallic"][v] for v in changed), 0.1)
        self.assertEqual(changed_in(self.base, painted, "roughness"), [])

    def test_constant_falloff_moves_more_than_sharp(self):
        def total(mesh):
            return sum(mesh.radius(v) - 1.0 for v in moved_vertices(self.base, mesh))
        constant = self.sculpt(Replay().key("d").key("f5").drag(*ACROSS))
        sharp = self.sculpt(Replay().key("d").key("f4").drag(*ACROSS))
        self.assertGreater(total(constant), 1.5 * total(sharp))

    def test_pen_pressure_scales_strength(self):
        def total(mesh):
            return sum(mesh.radius(v) - 1.0 for v in moved_vertices(self.base, mesh))
        light = self.sculpt(Replay().key("d").pressure(0.2).drag(*ACROSS))
        full = self.sculpt(Replay().key("d").pressure(1).drag(*ACROSS))
        self.assertGreater(total(light), 0.0)
        self.assertLess(total(light), 0.5 * total(full))

    def stroke_direction(self, replay):
        """The unit direction, from the sphere's centre, of the vertices a replay moved."""
        moved = moved_vertices(self.base, self.sculpt(replay))
        self.assertGreater(len(moved), 20)
        c = [mean(self.base.position(v)[k] for v in moved) for k in range(3)]
        length = sum(x * x for x in c) ** 0.5
        self.assertGreater(length, 0.8)  # around one point of the surface
        return [x / length for x in c]

    def test_front_side_and_top_views_look_along_three_axes(self):
        # The same stroke through the window's centre lands on three different poles.
        centre = ((630, 400), (650, 400))
        front = self.stroke_direction(Replay().key("d").key("x").drag(*centre))
        side = self.stroke_direction(Replay().key("3").key("d").key("x").drag(*centre))
        top = self.stroke_direction(Replay().key("7").key("d").key("x").drag(*centre))
        back_to_front = self.stroke_direction(Replay().key("7").key("1").key("d").key("x").drag(*centre))
        for a, b in ((front, side), (front, top), (side, top)):
            self.assertLess(abs(sum(x * y for x, y in zip(a, b))), 0.2)
        self.assertGreater(sum(x * y for x, y in zip(front, back_to_front)), 0.99)

    def test_front_faces_only_spares_the_far_side(self):
        # A wide draw along the right rim: the brush's ball reaches round the silhouette.
        front = self.stroke_direction(Replay().key("d").key("x").drag((630, 400), (650, 400)))

        def moved(*keys):
            replay = Replay().key("d").key("x")
            for k in ("]",) * 5 + keys:
                replay.key(k)
            return set(moved_vertices(self.base, self.sculpt(replay.drag((908, 380), (908, 420)))))

        def towards_eye(v):
            return sum(p * f for p, f in zip(self.base.position(v), front))
        front_only, all_faces = moved(), moved("v")  # on by default; V turns it off
        self.assertGreater(len(front_only), 50)
        beyond = all_faces - front_only
        self.assertGreater(len(beyond), 20)
        # What only the second stroke moved lies further round the rim than anything the
        # first moved: the faces turned away from the eye.
        self.assertLess(max(map(towards_eye, beyond)), min(map(towards_eye, front_only)) + 0.02)

    def test_radius_keys_widen_and_narrow_the_brush(self):
        def moved(*keys):
            replay = Replay().key("d").key("x")
            for k in keys:
                replay.key(k)
            return len(moved_vertices(self.base, self.sculpt(replay.drag(*ACROSS))))
        default, wider, narrower = moved(), moved("]", "]"), moved("[", "[")
        self.assertGreater(wider, 1.5 * default)
        self.assertLess(narrower, 0.75 * default)

    def test_z_symmetry_mirrors_through_the_sphere(self):
        # The view looks along one axis; Z mirrors across z = 0 wherever that is: a stroke
        # beside the front pole also moves the point mirrored through z = 0.
        replay = Replay().key("d").key("x").key("z").drag((700, 380), (740, 380))
        moved = moved_vertices(self.base, self.sculpt(replay))
        plain = moved_vertices(self.base, self.sculpt(Replay().key("d").key("x").drag((700, 380), (740, 380))))
        mirrored = {tuple(round(c, 4) for c in (p[0], p[1], -p[2])) for p in map(self.base.position, plain)}
        self.assertGreater(len(moved), 1.5 * len(plain))
        self.assertTrue(any(tuple(round(c, 4) for c in self.base.position(v)) in mirrored for v in moved
                            if v not in set(plain)))

    def test_replay_is_deterministic(self):
        first = self.sculpt(Replay().key("d").drag(*ACROSS))
        second = self.sculpt(Replay().key("d").drag(*ACROSS))
        self.assertEqual(first.raw, second.raw)


if __name__ == "__main__":
    unittest.main()
