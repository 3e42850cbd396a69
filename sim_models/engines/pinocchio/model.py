"""The Pinocchio model of a linkage (:class:`PinocchioModel`): the tree joints' frames,
the kinematic tree in depth-first order, the loop constraints and the Baumgarte gains
(the model is described in :mod:`sim_models.engines.pinocchio.driven`'s docstring)."""

from __future__ import annotations

import math

import numpy as np


def _rz(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _v3(p) -> np.ndarray:
    return np.array([float(p[0]), float(p[1]), 0.0])


def _couple(r, f, torque: float = 0.0) -> np.ndarray:
    """``r x f + (0, 0, torque)`` of in-plane vectors (z = 0): only z is nonzero
    (faster than ``np.cross``, which spends its time on axis handling here)."""
    return np.array([0.0, 0.0, r[0] * f[1] - r[1] * f[0] + torque])



class PinocchioModel:
    """Building a :class:`~sim_models.engines.pinocchio.driven.PinocchioSession`'s model
    and its loop constraints from the compiled linkage (``self.tree``)."""

    # ------------------------------------------------------------------ model
    def _frames(self):
        """World pose (R 3x3, origin 3) of each tree joint's frame at the reference, and
        each body's offset of its joint frame in its body frame (m)."""
        st = self.tree
        frames, offset = {}, {st.ground: np.zeros(2)}
        for tj in st.joints:
            c = tj.child
            off = tj.anchor_child if tj.kind == "hinge" else np.zeros(2)
            offset[c] = np.asarray(off, float)
            R = _rz(float(st.theta_ref[c]))
            frames[c] = (R, _v3(st.origin_ref[c]) + R @ _v3(off))
        return frames, offset

    def _build(self) -> None:
        pin, st = self.pin, self.tree
        model = pin.Model()
        g = st.mech.gravity
        model.gravity = pin.Motion(np.array([g[0], g[1], 0.0]), np.zeros(3))
        frames, self.offset = self._frames()
        self.jid = {st.ground: 0}
        world = pin.SE3.Identity()
        for tj in self._depth_first():
            p, c = tj.parent, tj.child
            oMp = world if p == st.ground else pin.SE3(*frames[p])
            oMc = pin.SE3(*frames[c])
            if tj.kind == "hinge":
                jm = pin.JointModelRZ()
            else:
                jm = pin.JointModelPrismaticUnaligned(_v3(tj.axis_child))
            jid = model.addJoint(self.jid[p], jm, oMp.actInv(oMc), tj.name)
            self.jid[c] = jid
            lever = _v3(np.asarray(st.com[c]) - self.offset[c])
            I = float(st.inertia[c])
            model.appendBodyToJoint(jid, pin.Inertia(float(st.mass[c]), lever,
                                                     np.diag([I, I, I])), pin.SE3.Identity())
        self.model = model
        self.data = model.createData()
        self.nv = model.nv
        self.vidx = np.array([model.joints[self.jid[tj.child]].idx_v for tj in st.joints])
        self.drive_v = int(self.vidx[st.driver_tree])
        self._constraints()
        self.prox = pin.ProximalSettings(float(self.settings.prox_accuracy),
                                         float(self.settings.prox_accuracy),
                                         float(self.settings.prox_mu),
                                         int(self.settings.prox_max_iter))
        self.loads = [(st.body_names.index(ld.body), ld) for ld in st.mech.loads]

    def _depth_first(self):
        """The tree joints depth first: Pinocchio's algorithms that use the joint-space
        sparsity (``crba``, the Cholesky of ``constraintDynamics``) need every subtree's
        joints contiguous (measured: in the tree's breadth-first order the seed
        four-bar's ``crba`` loses the crank-coupler coupling and the drive torque comes
        out -0.41 N m instead of 0.67 N m)."""
        st = self.tree
        out: list = []

        def visit(b):
            for tj in st.joints:
                if tj.parent == b:
                    out.append(tj)
                    visit(tj.child)
        visit(st.ground)
        return out

    def _constraints(self) -> None:
        """One ``CONTACT_3D`` per loop-closing joint, the moving body as joint 1;
        ``self.chord_sign`` turns its force into the force by body_a on body_b."""
        pin, st = self.pin, self.tree
        models = pin.StdVec_RigidConstraintModel()
        self.chord_sign = []
        for ch in st.chords:
            ends = [(ch.body_a, ch.point_a), (ch.body_b, ch.point_b)]
            first = 1 if ch.body_a == st.ground else 0   # the moving body as joint 1
            (b1, p1), (b2, p2) = ends[first], ends[1 - first]
            cm = pin.RigidConstraintModel(
                pin.ContactType.CONTACT_3D, self.model, self.jid[b1], self._placement(b1, p1),
                self.jid[b2], self._placement(b2, p2), pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
            cm.name = ch.name
            models.append(cm)
            # contact_force acts on joint 1: on body_b when body_b is joint 1
            self.chord_sign.append(1.0 if b1 == ch.body_b else -1.0)
        self.cmodels = models
        self.cdatas = pin.StdVec_RigidConstraintData()
        for cm in models:
            self.cdatas.append(cm.createData())
        self.ncon = 3 * len(models)
        pin.initConstraintDynamics(self.model, self.data, self.cmodels, self.cdatas)

    def _placement(self, b: int, point):
        """The joint point of body ``b`` in its joint's frame (ground: world)."""
        pin, st = self.pin, self.tree
        if b == st.ground:
            R = _rz(float(st.theta_ref[b]))
            return pin.SE3(np.eye(3), _v3(st.origin_ref[b]) + R @ _v3(point))
        return pin.SE3(np.eye(3), _v3(np.asarray(point, float) - self.offset[b]))

    def set_baumgarte(self, h: float) -> None:
        """Critically damped Baumgarte gains for step ``h`` (s): ``omega = baumgarte / h``,
        ``Kp = omega^2``, ``Kd = 2 omega``."""
        w = float(self.settings.baumgarte) / h if h > 0 else 0.0
        self._gains(w)

    def _gains(self, w: float) -> None:
        for cm in self.cmodels:
            cm.setBaumgarteCorrectorParameters(
                self.pin.BaumgarteCorrectorParameters(w * w, 2.0 * w))

