"""The Exudyn model of a linkage (:class:`ExudynModel`): the system, its bodies in the
reference pose, joints, drive and loads, assembled and indexed.  The model is described in
:mod:`sim_models.engines.exudyn.driven`'s docstring; the released session adds its force
elements (:mod:`sim_models.engines.exudyn.free`)."""

from __future__ import annotations

import math

import numpy as np

from analytic import Revolute

from .planar import _rot


class ExudynModel:
    """Building an :class:`~sim_models.engines.exudyn.driven.ExudynSession`'s Exudyn
    system from the compiled linkage (``self.tree``), one phase per item kind."""

    def _ref_point(self, b: int, r) -> np.ndarray:
        """World position (m) of offset ``r`` of body ``b`` in the reference pose."""
        if b == self.g:
            return _rot(float(self.tree.kin_ref.theta[0, self.g]), r)
        return self.ref[b][:2] + _rot(self.ref[b][2], r)


    def _build(self):
        self._add_drive(self._new_system())
        self._add_loads()
        self._assemble()
        self.drive_ae = int(self.mbs.systemData.GetObjectLTGAE(self.drive_obj)[0])

    def _new_system(self):
        """A new Exudyn system holding the ground, the bodies in the reference pose and the
        joints: what the driven and the released sessions share.  Returns the ground
        node (the drive's, or the released run's rotation markers')."""
        exu, st = self.exu, self.tree
        from exudyn import itemInterface as ii
        self.SC = exu.SystemContainer()
        mbs = self.mbs = self.SC.AddSystem()
        self.g = st.ground
        self.ground_obj = mbs.AddObject(ii.ObjectGround())
        ground_node = mbs.AddNode(ii.NodePointGround())
        self._add_bodies(mbs, st.kin_ref)
        self.joint_obj = [self._add_joint(jt) for jt in st.mech.joints]
        return ground_node

    def _assemble(self) -> None:
        """Assemble the system and index it: each body's ODE2 coordinates and reference
        coordinates, each joint's multipliers, the ODE2 size."""
        mbs = self.mbs
        mbs.Assemble()
        sd = mbs.systemData
        self.ltg = {b: np.array(sd.GetNodeLTGODE2(n)) for b, n in self.node.items()}
        self.ref = {b: np.array(mbs.GetNodeParameter(n, "referenceCoordinates"), float)
                    for b, n in self.node.items()}
        self.joint_ae = [np.array(sd.GetObjectLTGAE(o)) for o in self.joint_obj]
        self.n_ode2 = sd.ODE2Size()

    def _body_mass(self, b: int, body) -> tuple[float, float]:
        """Mass (kg) and inertia about the centre of mass (kg m^2) built for body ``b``."""
        st = self.tree
        if st.has_mass:  # exact: a massless link stays massless (module docstring)
            return float(body.mass), float(body.inertia)
        return float(st.mass[b]), float(st.inertia[b])

    def _add_bodies(self, mbs, kin) -> None:
        """One ``NodeRigidBody2D`` and ``ObjectRigidBody2D`` per moving body, in the
        reference pose ``kin`` (its first sample): fills ``node``, ``obj``, ``com``."""
        from exudyn import itemInterface as ii
        st = self.tree
        self.node, self.obj, self.com = {}, {}, {}
        for b, body in enumerate(st.mech.bodies):
            if b == self.g:
                continue
            m, inertia = self._body_mass(b, body)
            c = np.asarray(st.com[b], float)
            th = float(kin.theta[0, b])
            rG = kin.origin[0, b] + _rot(th, c)
            n = mbs.AddNode(ii.NodeRigidBody2D(referenceCoordinates=[rG[0], rG[1], th],
                                               initialCoordinates=[0.0, 0.0, 0.0],
                                               initialVelocities=[0.0, 0.0, 0.0]))
            self.obj[b] = mbs.AddObject(ii.ObjectRigidBody2D(mass=m, inertia=inertia,
                                                             nodeNumber=n))
            self.node[b], self.com[b] = n, c

    def _marker(self, b: int, p):
        """A rigid marker at body-frame point ``p`` (m) of body ``b``."""
        from exudyn import itemInterface as ii
        p = np.asarray(p, float)
        if b == self.g:
            return self.mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=self.ground_obj,
                                                         localPosition=[p[0], p[1], 0.0]))
        r = p - self.com[b]
        return self.mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=self.obj[b],
                                                     localPosition=[r[0], r[1], 0.0]))

    def _add_joint(self, jt):
        from exudyn import itemInterface as ii
        st = self.tree
        idx = {n: i for i, n in enumerate(st.body_names)}
        a, b = idx[jt.body_a], idx[jt.body_b]
        ma = self._marker(a, st.mech.bodies[a].points[jt.point_a])
        mb = self._marker(b, st.mech.bodies[b].points[jt.point_b])
        if isinstance(jt, Revolute):
            return self.mbs.AddObject(ii.RevoluteJoint2D(markerNumbers=[ma, mb]))
        d = jt.direction
        nn = d + math.pi / 2 - jt.angle  # the line normal in the slider frame
        return self.mbs.AddObject(ii.PrismaticJoint2D(
            markerNumbers=[ma, mb], axisMarker0=[math.cos(d), math.sin(d), 0.0],
            normalMarker1=[math.cos(nn), math.sin(nn), 0.0], constrainRotation=True))

    def _add_drive(self, ground_node):
        from exudyn import itemInterface as ii
        st, mbs = self.tree, self.mbs
        mech = st.mech
        d, djt = mech.driver, mech.driver_joint
        idx = {n: i for i, n in enumerate(st.body_names)}
        m_ground = mbs.AddMarker(ii.MarkerNodeCoordinate(nodeNumber=ground_node, coordinate=0))
        self.sigma = None
        self._drive_a = self._drive_b = None
        if isinstance(djt, Revolute):
            a, b = idx[djt.body_a], idx[djt.body_b]
            self._drive_a, self._drive_b = a, b
            m0, m1 = (m_ground if x == self.g else mbs.AddMarker(
                ii.MarkerNodeCoordinate(nodeNumber=self.node[x], coordinate=2)) for x in (a, b))
        else:
            # sigma (displacement s - s_ref) is a massless coordinate tied to the slider's
            # displacement along the (ground) line; the drive constrains sigma
            sb = idx[djt.slider]
            u = np.array([math.cos(djt.direction), math.sin(djt.direction)])
            # MarkerNodeCoordinates carries total coordinates (reference + displacement)
            # into the CoordinateVector constraint: sigma's reference is u . x_G,ref
            s_ref = float(u @ mbs.GetNodeParameter(self.node[sb], "referenceCoordinates")[:2])
            self.sigma = mbs.AddNode(ii.NodeGenericODE2(referenceCoordinates=[s_ref],
                                                        initialCoordinates=[0.0],
                                                        initialCoordinates_t=[0.0],
                                                        numberOfODE2Coordinates=1))
            mbs.AddObject(ii.ObjectGenericODE2(nodeNumbers=[self.sigma],
                                               massMatrixUserFunction=0,
                                               massMatrix=np.zeros((1, 1))))
            mx = mbs.AddMarker(ii.MarkerNodeCoordinates(nodeNumber=self.node[sb]))
            ms = mbs.AddMarker(ii.MarkerNodeCoordinates(nodeNumber=self.sigma))
            # measured: the equation is X1 q1 - X0 q0 = 0, i.e. sigma = u . x_G
            mbs.AddObject(ii.ObjectConnectorCoordinateVector(
                markerNumbers=[mx, ms], scalingMarker0=np.array([[u[0], u[1], 0.0]]),
                scalingMarker1=np.array([[1.0]]), offset=[0.0]))
            m0 = m_ground
            m1 = mbs.AddMarker(ii.MarkerNodeCoordinate(nodeNumber=self.sigma, coordinate=0))
            self.drive_u = u
        w0, acc = float(d.velocity), float(d.acceleration)
        if acc == 0.0:
            self.drive_obj = mbs.AddObject(ii.CoordinateConstraint(
                markerNumbers=[m0, m1], offset=w0, velocityLevel=True))
            return

        def rate(mbs, t, item, offset):  # the prescribed driver rate at time t
            return w0 + acc * t

        self.drive_obj = mbs.AddObject(ii.CoordinateConstraint(
            markerNumbers=[m0, m1], velocityLevel=True, offsetUserFunction_t=rate))
        # the same function as a compiled expression tree (no Python call per Newton
        # iteration; measured 10-17 us a step, 15-20% of it); kept alive with the session
        from exudyn.utilities import CreateSymbolicUserFunction
        self._rate_fn = CreateSymbolicUserFunction(mbs, rate, "offsetUserFunction_t",
                                                   self.drive_obj)
        mbs.SetObjectParameter(self.drive_obj, "offsetUserFunction_t", self._rate_fn)

    def _add_loads(self):
        from exudyn import itemInterface as ii
        st, mbs = self.tree, self.mbs
        mech = st.mech
        gx, gy = mech.gravity
        if gx or gy:
            for b, o in self.obj.items():
                if mech.bodies[b].mass or not st.has_mass:
                    mk = mbs.AddMarker(ii.MarkerBodyMass(bodyNumber=o))
                    mbs.AddLoad(ii.LoadMassProportional(markerNumber=mk,
                                                        loadVector=[gx, gy, 0.0]))
        idx = {n: i for i, n in enumerate(st.body_names)}
        for ld in mech.loads:
            b = idx[ld.body]
            if b == self.g:  # a load on the ground moves nothing
                continue
            body = mech.bodies[b]
            p = body.points[ld.point] if ld.point is not None else self.com[b]
            mk = self._marker(b, p)
            if ld.force[0] or ld.force[1]:
                mbs.AddLoad(ii.LoadForceVector(markerNumber=mk,
                                               loadVector=[ld.force[0], ld.force[1], 0.0]))
            if ld.torque:
                mbs.AddLoad(ii.LoadTorqueVector(markerNumber=mk,
                                                loadVector=[0.0, 0.0, ld.torque]))

