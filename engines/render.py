"""The frames of an animation: where the scene's bodies are at each frame (MuJoCo's forward kinematics of a
run's states), and MuJoCo's own renderer for them.

The scenes carry no geoms (their bodies are masses and inertias on joints), so what is drawn is a skeleton
made from the bodies: a line from each body's origin to what hangs on it (its children's origins, its
centre of mass, the anchors of its loops), a dot at each massive body's centre of mass, and for a body with
a full inertia (a rigid body, not a point mass or a rod) the rim of the uniform disk that has its largest
principal moment, about that axis.  Both renderers draw this skeleton: matplotlib (dyncheck.pages.animation)
from the arrays saved in the results, MuJoCo's renderer (`MujocoPainter`) with its own shading.
"""

import numpy as np

import mujoco

PLACEHOLDER = 1e-9  # kg and kg m^2: below, a mass or inertia is the placeholder MuJoCo needs, not the physics
RIM_POINTS = 48


def skeleton(model, times, q):
    """The skeleton of `model` (engines.mujoco_adapter.MujocoModel) at each state (times[i], q[i]): segments
    (frame, segment, 2, 3), dots (frame, dot, 3), the dots' masses (dot,), rims (frame, rim, RIM_POINTS, 3),
    world coordinates in m."""
    m = model.m
    bodies = range(1, m.nbody)
    massive = [b for b in bodies if m.body_mass[b] > PLACEHOLDER]
    solid = [b for b in massive if np.all(m.body_inertia[b] > PLACEHOLDER)]
    anchors = [(int(m.eq_obj1id[e]), m.eq_data[e, :3].copy()) for e in range(m.neq)
               if m.eq_type[e] == mujoco.mjtEq.mjEQ_CONNECT]
    segments, dots, rims = [], [], []
    for t, qi in zip(times, q):
        model.points(t, qi)  # the adapter's state conversion (loops closed), then mj_kinematics on model.d
        d = model.d
        ends = [(d.xpos[m.body_parentid[b]], d.xpos[b]) for b in bodies]
        ends += [(d.xpos[b], d.xipos[b]) for b in massive]
        ends += [(d.xpos[b], d.xpos[b] + d.xmat[b].reshape(3, 3) @ anchor) for b, anchor in anchors]
        segments.append(np.array(ends))  # a copy: d's rows change with the next state
        dots.append(d.xipos[massive])
        rims.append([rim(m, d, b) for b in solid])
    shape = lambda rows, count, tail: np.array(rows, dtype=float).reshape(len(times), count, *tail)
    segments = shape(segments, len(bodies) + len(massive) + len(anchors), (2, 3))
    drawn = np.linalg.norm(segments[:, :, 1] - segments[:, :, 0], axis=-1).max(axis=0, initial=0.0) > 1e-12
    return (segments[:, drawn], shape(dots, len(massive), (3,)), m.body_mass[massive].copy(),
            shape(rims, len(solid), (RIM_POINTS, 3)))


def rim(m, d, body):
    """The rim of the uniform disk with `body`'s mass and largest principal moment I (radius sqrt(2 I / m)),
    centred on its centre of mass, about that principal axis: (RIM_POINTS, 3)."""
    axis = int(np.argmax(m.body_inertia[body]))
    radius = np.sqrt(2 * m.body_inertia[body][axis] / m.body_mass[body])
    plane = [i for i in range(3) if i != axis]
    angles = np.linspace(0.0, 2 * np.pi, RIM_POINTS)
    local = np.zeros((RIM_POINTS, 3))
    local[:, plane[0]], local[:, plane[1]] = radius * np.cos(angles), radius * np.sin(angles)
    return d.xipos[body] + local @ d.ximat[body].reshape(3, 3).T


class MujocoPainter:
    """MuJoCo's renderer (an OpenGL context: MUJOCO_GL=egl or osmesa) drawing a skeleton's frames as capsules,
    spheres and arrows, seen from a camera at `azimuth`, `elevation` (degrees) looking at `centre` from
    `distance` (m).  Raises where no context opens (mujoco.FatalError, RuntimeError)."""

    def __init__(self, width, height):
        self.model = mujoco.MjModel.from_xml_string(
            '<mujoco><visual><global offwidth="2000" offheight="2000"/>'
            '<headlight ambient=".6 .6 .6" diffuse=".5 .5 .5"/></visual>'
            '<worldbody><light pos="0 0 3" dir="0 0 -1" directional="true"/></worldbody></mujoco>')
        self.data = mujoco.MjData(self.model)
        self.renderer = mujoco.Renderer(self.model, height, width)

    def image(self, view, segments, dots, sizes, rims, arrows=(), colours=None):
        """An RGB image (height, width, 3) of one frame: `view` (centre, distance, azimuth, elevation),
        segments (n, 2, 3), dots (n, 3) with radii `sizes` (m), rims (n, k, 3), arrows (start, end) pairs;
        `colours` {kind: rgba} for "segment", "dot", "rim", "arrow"."""
        colours = colours or {}
        camera = mujoco.MjvCamera()
        camera.lookat[:], camera.distance, camera.azimuth, camera.elevation = view
        self.renderer.update_scene(self.data, camera)
        scene = self.renderer.scene
        width = 0.006 * view[1]  # the lines' radius: a fixed share of the view
        for a, b in segments:
            self._connector(scene, mujoco.mjtGeom.mjGEOM_CAPSULE, width, a, b, colours.get("segment", (.75, .75, .75, 1)))
        for ring in rims:
            for a, b in zip(ring[:-1], ring[1:]):
                self._connector(scene, mujoco.mjtGeom.mjGEOM_CAPSULE, width / 2, a, b, colours.get("rim", (.3, .8, .3, 1)))
        for a, b in arrows:
            self._connector(scene, mujoco.mjtGeom.mjGEOM_ARROW, width, a, b, colours.get("arrow", (.7, .3, .9, 1)))
        for point, size in zip(dots, sizes):
            geom = self._geom(scene)
            mujoco.mjv_initGeom(geom, mujoco.mjtGeom.mjGEOM_SPHERE, np.full(3, size), point, np.eye(3).ravel(),
                                np.array(colours.get("dot", (.95, .6, .2, 1)), dtype=np.float32))
        return self.renderer.render()

    @staticmethod
    def _geom(scene):
        if scene.ngeom >= scene.maxgeom:
            raise ValueError(f"MuJoCo's scene holds at most {scene.maxgeom} geoms")
        scene.ngeom += 1
        return scene.geoms[scene.ngeom - 1]

    def _connector(self, scene, kind, width, a, b, rgba):
        geom = self._geom(scene)
        mujoco.mjv_initGeom(geom, kind, np.zeros(3), np.zeros(3), np.eye(3).ravel(), np.array(rgba, dtype=np.float32))
        mujoco.mjv_connector(geom, kind, width, np.asarray(a, dtype=float), np.asarray(b, dtype=float))

    def close(self):
        self.renderer.close()
