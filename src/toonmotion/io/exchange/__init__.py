"""Exchange formats for other tools: glTF (binary ``.glb``) export of 3D proxies."""
