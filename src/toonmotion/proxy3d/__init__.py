"""3D proxies for hand-drawn characters (Jain et al. 2012, "Three-Dimensional Proxies for
Hand-Drawn Characters").

The first slice: the drawing's 2D markers (:mod:`~toonmotion.proxy3d.markers`), a motion-capture
prior matched to them (:mod:`~toonmotion.proxy3d.prior`), time alignment by dynamic time warping
(:mod:`~toonmotion.proxy3d.timewarp`, section 3.1.2), the orthographic camera and a search for
it (:mod:`~toonmotion.proxy3d.orthographic`, 3.1.3), and the pose descriptor with the prior's
modification (:mod:`~toonmotion.proxy3d.descriptor`, 3.2). See docs/proxy3d.md.

Frames: drawn markers are ``(x, y)`` drawing pixels, y down; 3D is right-handed, y up, in the
prior's units.
"""
