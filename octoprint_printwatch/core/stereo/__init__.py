"""Two-camera stereo in relaxed geometry: rectification, matching, triangulation, the size check.

* :mod:`.rectify` — calibrated (``cv2.stereoRectify`` from the printer-frame extrinsics),
  uncalibrated (SIFT + RANSAC + ``cv2.stereoRectifyUncalibrated``) and the seed's
  rescale + vertical shift (Eqs. A-1..A-4), each reporting whether it can be trusted.
* :mod:`.matching` — the seed's SAD block matcher (Eq. 1-7 / 2-1), SSD, NCC, ``cv2.StereoSGBM``.
* :mod:`.triangulate` — the seed's relaxed-geometry equations (Eqs. 2-2..2-14) and the general form.
* :mod:`.size_check` — width at the current print height and printed height vs the model (seed ch. 5).
"""
from .size_check import PairSizeCheck, SizeResult, SizeSettings

__all__ = ["PairSizeCheck", "SizeResult", "SizeSettings"]
