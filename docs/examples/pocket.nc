(square pocket contour with rounded corners)
G21 G90 G17
G0 X-50 Y-40 Z5
G1 Z0 F600
G1 X40 F1200
G3 X50 Y-30 R10
G1 Y30
G3 X40 Y40 I-10 J0
G1 X-40
G3 X-50 Y30 R10
G1 Y-30
G3 X-40 Y-40 I10 J0   ; back to the start of the contour
G0 Z5
