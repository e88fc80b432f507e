"""Picking the first box by eye: ``vtrack select`` (a box dragged in a browser page) and
``vtrack frame`` (one frame with a pixel grid to read coordinates off).

- :mod:`.frames`: frames of an input by index, decoded once and kept encoded;
- :mod:`.grid`: the light pixel grid and its scale labels;
- :mod:`.server`: the local page (stdlib ``http.server``) that returns the dragged box.
"""
