"""Pinhole camera with lens distortion, in OpenCV's conventions.

Printer coordinates are millimetres with Z up and the bed top at z = 0.
``rvec``/``tvec`` map printer coordinates to camera coordinates,
``x_cam = R(rvec) @ X_printer + tvec`` (x right, y down, z forward), exactly as
``docs/recording-format.md`` specifies, so a :class:`Camera` round-trips through
a recording's ``session.json`` unchanged.
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import cv2
import numpy as np

#: Version written into stand-alone camera JSON files (calibration output).
CAMERA_FILE_FORMAT = "printwatch-camera/1"


class CameraError(ValueError):
    """A camera description that cannot be used; the message says what is wrong."""


def _matrix(value: Any, shape: tuple[int, ...], what: str) -> np.ndarray:
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise CameraError(f"{what} is not numeric: {exc}") from None
    if array.size != int(np.prod(shape)):
        raise CameraError(f"{what} must have {int(np.prod(shape))} numbers, got {array.size}")
    array = array.reshape(shape)
    if not np.all(np.isfinite(array)):
        raise CameraError(f"{what} contains NaN or infinity")
    return array


@dataclass
class Camera:
    """One calibrated camera.

    Attributes
    ----------
    name : str
        Identifier used in recordings (``cam0L`` ...).
    width, height : int
        Image size in pixels.
    K : (3, 3) float
        Intrinsic matrix in pixels.
    dist : (n,) float
        Distortion coefficients as ``cv2.calibrateCamera`` returns them (n in 4, 5, 8, 12, 14).
    rvec, tvec : (3,) float
        Rodrigues rotation and translation from printer to camera coordinates (mm).
    """

    name: str
    width: int
    height: int
    K: np.ndarray
    dist: np.ndarray = field(default_factory=lambda: np.zeros(5))
    rvec: np.ndarray = field(default_factory=lambda: np.zeros(3))
    tvec: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self) -> None:
        self.width = int(self.width)
        self.height = int(self.height)
        if self.width <= 0 or self.height <= 0:
            raise CameraError(f"camera {self.name}: image size must be positive, got {self.width}x{self.height}")
        self.K = _matrix(self.K, (3, 3), f"camera {self.name}: K")
        if self.K[0, 0] <= 0 or self.K[1, 1] <= 0:
            raise CameraError(f"camera {self.name}: focal lengths in K must be positive")
        dist = np.asarray(self.dist if self.dist is not None else [], dtype=np.float64).ravel()
        if dist.size == 0:
            dist = np.zeros(5)
        if dist.size not in (4, 5, 8, 12, 14):
            raise CameraError(f"camera {self.name}: dist must have 4, 5, 8, 12 or 14 coefficients, got {dist.size}")
        self.dist = _matrix(dist, (dist.size,), f"camera {self.name}: dist")
        self.rvec = _matrix(self.rvec, (3,), f"camera {self.name}: rvec")
        self.tvec = _matrix(self.tvec, (3,), f"camera {self.name}: tvec")

    # ----------------------------------------------------------------- pose
    @property
    def R(self) -> np.ndarray:
        """(3, 3) rotation from printer to camera coordinates."""
        return cv2.Rodrigues(self.rvec)[0]

    @property
    def center(self) -> np.ndarray:
        """(3,) camera centre in printer coordinates (mm)."""
        return -self.R.T @ self.tvec

    @property
    def viewing_direction(self) -> np.ndarray:
        """(3,) unit optical axis in printer coordinates."""
        return self.R.T @ np.array([0.0, 0.0, 1.0])

    @property
    def size(self) -> tuple[int, int]:
        """(width, height), the order OpenCV functions take."""
        return (self.width, self.height)

    @classmethod
    def look_at(
        cls,
        name: str,
        eye: Any,
        target: Any,
        *,
        width: int = 640,
        height: int = 480,
        focal_px: float | None = None,
        hfov_deg: float = 60.0,
        dist: Any = None,
        up: Any = (0.0, 0.0, 1.0),
        roll_deg: float = 0.0,
    ) -> "Camera":
        """Camera at ``eye`` (mm, printer coordinates) looking at ``target``, image up ~ printer +Z.

        ``focal_px`` wins over ``hfov_deg`` (horizontal field of view) when both are given.
        """
        eye = np.asarray(eye, dtype=np.float64)
        forward = np.asarray(target, dtype=np.float64) - eye
        if np.linalg.norm(forward) == 0:
            raise CameraError(f"camera {name}: eye and target coincide")
        forward /= np.linalg.norm(forward)
        right = np.cross(forward, np.asarray(up, dtype=np.float64))
        if np.linalg.norm(right) < 1e-9:  # looking straight along `up`
            right = np.cross(forward, np.array([0.0, 1.0, 0.0]))
        right /= np.linalg.norm(right)
        down = np.cross(forward, right)
        R = np.stack([right, down, forward])  # rows: camera axes in printer coordinates
        if roll_deg:
            a = np.radians(roll_deg)
            roll = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
            R = roll @ R
        if focal_px is None:
            focal_px = (width / 2.0) / np.tan(np.radians(hfov_deg) / 2.0)
        K = np.array([[focal_px, 0, (width - 1) / 2.0], [0, focal_px, (height - 1) / 2.0], [0, 0, 1]])
        rvec = cv2.Rodrigues(R)[0].ravel()
        tvec = -R @ eye
        return cls(name=name, width=width, height=height, K=K,
                   dist=np.zeros(5) if dist is None else dist, rvec=rvec, tvec=tvec)

    # ----------------------------------------------------------- projection
    def to_camera(self, points: Any) -> np.ndarray:
        """(n, 3) printer points -> (n, 3) camera coordinates."""
        pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        return pts @ self.R.T + self.tvec

    def project(self, points: Any, *, distorted: bool = True) -> np.ndarray:
        """(n, 3) printer points -> (n, 2) pixel coordinates.

        With ``distorted=False`` the pixels are those of the undistorted image
        (same ``K``, no lens distortion). Points behind the camera get NaN.
        """
        pts = np.ascontiguousarray(np.asarray(points, dtype=np.float64).reshape(-1, 3))  # (cv2 needs contiguous)
        if len(pts) == 0:
            return np.zeros((0, 2))
        cam = self.to_camera(pts)
        behind = cam[:, 2] <= 1e-6
        if distorted:
            uv = cv2.projectPoints(pts, self.rvec, self.tvec, self.K, self.dist)[0].reshape(-1, 2)
        else:
            z = np.where(behind, 1.0, cam[:, 2])
            uv = (cam[:, :2] / z[:, None]) @ self.K[:2, :2].T + self.K[:2, 2]
        uv[behind] = np.nan
        return uv

    def undistort_points(self, pixels: Any) -> np.ndarray:
        """(n, 2) distorted pixels -> (n, 2) pixels of the undistorted image (same K)."""
        px = np.asarray(pixels, dtype=np.float64).reshape(-1, 1, 2)
        if len(px) == 0:
            return np.zeros((0, 2))
        return cv2.undistortPoints(px, self.K, self.dist, P=self.K).reshape(-1, 2)

    def rays(self, pixels: Any, *, distorted: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """Viewing rays through pixels: ``(origin (3,), directions (n, 3) unit, printer frame)``."""
        px = np.asarray(pixels, dtype=np.float64).reshape(-1, 2)
        if distorted:
            norm = cv2.undistortPoints(px.reshape(-1, 1, 2), self.K, self.dist).reshape(-1, 2)
        else:
            norm = (px - self.K[:2, 2]) / np.diag(self.K)[:2]
        d_cam = np.column_stack([norm, np.ones(len(norm))])
        d = d_cam @ self.R  # R.T applied to each row
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        return self.center, d

    def unproject_to_plane(self, pixels: Any, z: float = 0.0, *, distorted: bool = True) -> np.ndarray:
        """(n, 2) pixels -> (n, 3) printer points where their rays meet the plane Z = z.

        Rays parallel to the plane or meeting it behind the camera give NaN.
        """
        origin, d = self.rays(pixels, distorted=distorted)
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (z - origin[2]) / d[:, 2]
        t = np.where((t > 0) & np.isfinite(t), t, np.nan)
        return origin + d * t[:, None]

    def unproject_depth(self, pixels: Any, depth: Any, *, distorted: bool = True) -> np.ndarray:
        """(n, 2) pixels and (n,) camera-frame depths (mm along the optical axis) -> (n, 3) printer points."""
        px = np.asarray(pixels, dtype=np.float64).reshape(-1, 2)
        depth = np.asarray(depth, dtype=np.float64).reshape(-1)
        if distorted:
            norm = cv2.undistortPoints(px.reshape(-1, 1, 2), self.K, self.dist).reshape(-1, 2)
        else:
            norm = (px - self.K[:2, 2]) / np.diag(self.K)[:2]
        cam = np.column_stack([norm * depth[:, None], depth])
        return (cam - self.tvec) @ self.R

    # ----------------------------------------------------------- images
    def undistort_maps(self) -> tuple[np.ndarray, np.ndarray]:
        """Remap tables taking a distorted frame to the undistorted image with the same K."""
        return cv2.initUndistortRectifyMap(self.K, self.dist, None, self.K, self.size, cv2.CV_32FC1)

    def undistort_image(self, image: np.ndarray, *, interpolation: int = cv2.INTER_LINEAR) -> np.ndarray:
        """Undistorted copy of a frame of this camera (same K, same size)."""
        if not np.any(self.dist):
            return image.copy()
        map1, map2 = self.undistort_maps()
        return cv2.remap(image, map1, map2, interpolation)

    def distort_image(self, undistorted: np.ndarray, *, interpolation: int = cv2.INTER_LINEAR) -> np.ndarray:
        """Inverse of :meth:`undistort_image`: warp an ideal-pinhole image into this lens's distorted view."""
        if not np.any(self.dist):
            return undistorted.copy()
        u, v = np.meshgrid(np.arange(self.width, dtype=np.float64), np.arange(self.height, dtype=np.float64))
        ideal = self.undistort_points(np.column_stack([u.ravel(), v.ravel()]))
        map_x = ideal[:, 0].reshape(self.height, self.width).astype(np.float32)
        map_y = ideal[:, 1].reshape(self.height, self.width).astype(np.float32)
        return cv2.remap(undistorted, map_x, map_y, interpolation)

    # ------------------------------------------------------- serialization
    def to_dict(self) -> dict:
        """The camera's fields exactly as a recording's ``session.json`` holds them (without the name)."""
        return {
            "width": self.width,
            "height": self.height,
            "K": self.K.tolist(),
            "dist": self.dist.tolist(),
            "rvec": self.rvec.tolist(),
            "tvec": self.tvec.tolist(),
        }

    @classmethod
    def from_dict(cls, name: str, data: Mapping[str, Any]) -> "Camera":
        if not isinstance(data, Mapping):
            raise CameraError(f"camera {name}: expected an object, got {type(data).__name__}")
        missing = [key for key in ("width", "height", "K") if key not in data]
        if missing:
            raise CameraError(f"camera {name}: missing {', '.join(missing)}")
        try:
            return cls(
                name=name,
                width=data["width"],
                height=data["height"],
                K=data["K"],
                dist=data.get("dist") or np.zeros(5),
                rvec=data.get("rvec", np.zeros(3)),
                tvec=data.get("tvec", np.zeros(3)),
            )
        except (TypeError, ValueError) as exc:
            if isinstance(exc, CameraError):
                raise
            raise CameraError(f"camera {name}: {exc}") from None

    def save(self, path: str | Path, **extra: Any) -> None:
        """Write a stand-alone, versioned camera file (calibration output); ``extra`` keys are kept."""
        doc = {"format": CAMERA_FILE_FORMAT, "name": self.name, **self.to_dict(), **extra}
        path = Path(path)
        tmp = path.with_name(path.name + ".tmp")
        tmp.write_text(json.dumps(doc, indent=2))
        tmp.replace(path)

    @classmethod
    def load(cls, path: str | Path, name: str | None = None) -> "Camera":
        path = Path(path)
        try:
            doc = json.loads(path.read_text())
        except FileNotFoundError:
            raise CameraError(f"{path}: no such file") from None
        except (OSError, ValueError) as exc:
            raise CameraError(f"{path}: not a readable camera JSON file ({exc})") from None
        fmt = doc.get("format", CAMERA_FILE_FORMAT) if isinstance(doc, dict) else None
        if fmt != CAMERA_FILE_FORMAT:
            raise CameraError(f"{path}: unsupported camera file format {fmt!r}")
        try:
            return cls.from_dict(name or doc.get("name") or path.stem, doc)
        except CameraError as exc:
            raise CameraError(f"{path}: {exc}") from None

    def with_pose(self, rvec: Any, tvec: Any) -> "Camera":
        return Camera(self.name, self.width, self.height, self.K.copy(), self.dist.copy(), rvec, tvec)

    def scaled(self, width: int, height: int) -> "Camera":
        """The same camera for frames resized to ``width`` x ``height``."""
        sx, sy = width / self.width, height / self.height
        K = self.K.copy()
        K[0] *= sx
        K[1] *= sy
        return Camera(self.name, width, height, K, self.dist.copy(), self.rvec.copy(), self.tvec.copy())
