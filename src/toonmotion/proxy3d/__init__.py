"""3D proxies for hand-drawn characters (Jain et al. 2012, "Three-Dimensional Proxies for
Hand-Drawn Characters").

Inputs: the drawing's 2D markers (:mod:`~toonmotion.proxy3d.markers`) and a motion-capture prior
matched to them (:mod:`~toonmotion.proxy3d.prior`). Preprocessing: time alignment by dynamic
time warping (:mod:`~toonmotion.proxy3d.timewarp`, section 3.1.2), the orthographic camera and a
search for it (:mod:`~toonmotion.proxy3d.orthographic`, 3.1.3), the pose descriptor with the
prior's modification (:mod:`~toonmotion.proxy3d.descriptor`, 3.2). The proxy: a perspective
camera per frame (:mod:`~toonmotion.proxy3d.camera`, :mod:`~toonmotion.proxy3d.camera_fit`,
3.3), point trajectories (:mod:`~toonmotion.proxy3d.points`, 3.4.1), collision volumes
(:mod:`~toonmotion.proxy3d.volumes`, 3.4.2), the skeleton (:mod:`~toonmotion.proxy3d.skeleton`,
3.4.3; as BVH: :mod:`~toonmotion.proxy3d.skeleton_bvh`), gathered in a
:class:`~toonmotion.proxy3d.proxy.Proxy` by :func:`~toonmotion.proxy3d.lift.lift`. See
docs/proxy3d.md.

Frames: drawn markers are ``(x, y)`` drawing pixels, y down; 3D is right-handed, y up, metres
once :func:`~toonmotion.proxy3d.prior.prior_in_metres` has converted the prior.
"""
