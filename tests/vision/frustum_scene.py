"""A frustum seen from the front by one camera looking down at it: the scene of the layer-shift height-null tests.

Seen from above, the part as expected at the previous check shows its top face (rows 88-110) and the band printed
since stands on it, narrower: only the band's top (rows 80-88) sticks out of the older layers' outline."""
import numpy as np

SHAPE = (220, 320)
CENTRE = 160
J = [[0.0, 4.0], [2.0, 0.0]]      # image px per printer X / Y mm at the part: printer X towards the camera (down)
HEIGHT = [0.0, -3.0]              # a part 1 mm taller: its top 3 px up
MIN_DX = 6                        # 1.5 mm sideways


def frustum(top: int, bottom: int, half_width_at_top: int, dx: int = 0, dy: int = 0) -> np.ndarray:
    """A frustum seen from the front: rows top..bottom, 1 px wider per row down each side, moved by (dx, dy)."""
    mask = np.zeros(SHAPE, bool)
    for row in range(top, bottom):
        half = half_width_at_top + (row - top)
        mask[row + dy, CENTRE - half + dx: CENTRE + half + dx] = True
    return mask


BEFORE = frustum(88, 170, 52)
BAND = frustum(80, 140, 30)
