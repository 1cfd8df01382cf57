"""The user's side of the library's boundary, shared by the command line and the demos.

:mod:`.coordinates`: how poses and actuator values appear to a user (lengths in a unit, angles
in degrees, pose columns of each family); :mod:`.describe`: the JSON-ready description of a
machine (``pkmkit show``, the demo's summaries). SI inside, units only here.
"""
