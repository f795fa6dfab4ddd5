"""Camera calibration a hobbyist can finish in ten minutes (issue 7).

- :func:`calibrate_intrinsics`: K and distortion from 10-15 board views, with a verdict.
- :mod:`.quick`: the seed's quick focal estimate (Eq. 5.1-5.4) when nothing better exists.
- :func:`calibrate_bed_pose`: the camera's pose in printer coordinates from a board on the bed.
- :func:`calibrate_pair`: two cameras' relative pose, and its consistency with their bed poses.
- :func:`check_pose_against_first_layer`: has the camera moved since? (during printing)
"""
from .bed import BedPoseResult, BoardPlacement, calibrate_bed_pose
from .images import load_image, load_images
from .intrinsics import IntrinsicsResult, calibrate_intrinsics, estimate_blur_sigma
from .pair import PairConsistency, PairResult, calibrate_pair, check_pair_consistency, relative_pose
from .quick import (QuickFocal, estimate_focal_from_image, focal_mm_from_px, focal_px_from_fov,
                    focal_px_from_square, pixel_size_um, quick_camera)
from .selfcheck import (PoseCheck, change_mask, check_pose_against_first_layer, first_layer_mask,
                        first_layer_paths, refine_pose_from_shift)

__all__ = [
    "BedPoseResult", "BoardPlacement", "calibrate_bed_pose",
    "load_image", "load_images",
    "IntrinsicsResult", "calibrate_intrinsics", "estimate_blur_sigma",
    "PairConsistency", "PairResult", "calibrate_pair", "check_pair_consistency", "relative_pose",
    "QuickFocal", "estimate_focal_from_image", "focal_mm_from_px", "focal_px_from_fov",
    "focal_px_from_square", "pixel_size_um", "quick_camera",
    "PoseCheck", "change_mask", "check_pose_against_first_layer", "first_layer_mask", "first_layer_paths",
    "refine_pose_from_shift",
]
