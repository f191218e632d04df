"""Mission export: a :class:`~wrp_eval.planning.path.FlightPath` in the ship frame -> flyable waypoint missions.

Ship frame (x bow, y port, z up above the sea) -> geographic coordinates through the ship's position and
true heading (:mod:`wrp_eval.frames`), then one mission per battery sortie (:mod:`.mission`) written as a
QGroundControl ``.plan``, a ``QGC WPL 110`` text file, a DJI WPML KMZ or a Litchi CSV (:mod:`.formats`),
each with a reader for round trips. ``wrp-eval export`` is the command (``wrp_eval/cli/export.py``).
"""
