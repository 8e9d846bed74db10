"""3D elements simulated around a proxy (Jain et al. 2012, section 3.5): what the elements are
(``elements.py``), the MuJoCo model of the proxy and the elements (``build.py``) and the
simulation through the drawn frames (``simulate.py``). Rendering and compositing are in
``render/``; docs/scene3d.md explains the whole."""
