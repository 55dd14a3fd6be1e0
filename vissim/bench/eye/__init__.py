"""The eye bench: a letter chart at a distance seen by a schematic eye through trial lenses.

`bench` holds its geometry (`EyeBench`: the chart, the lens stack in front of the eye, the eye
sensor's settings), `scene` its Mitsuba scene dict (`eye_scene`) and `sensor_eyes` the eyes handed
to the ``vissim_schematic_eye`` sensor.  The lens holder's rules and the chart's are shared with the
DSLR bench (`vissim.bench.lenses.holder`, `vissim.bench.scene_parts`); none of the DSLR's camera is
borrowed.
"""
