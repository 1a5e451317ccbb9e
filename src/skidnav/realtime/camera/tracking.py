"""Robot pose from an overhead camera tracking ArUco markers (docs/camera.md).

:class:`CameraPoseSource` turns frames (from :func:`open_frames`) and a floor calibration (from
:func:`calibrate` or :func:`load_calibration`, optionally made with the lens model of
:func:`calibrate_intrinsics` / :func:`load_intrinsics`) into
:class:`~skidnav.realtime.link.interface.Pose` measurements, either frame by frame
(:meth:`CameraPoseSource.process`) or continuously in a background thread
(:meth:`CameraPoseSource.start`) for the real-time loop.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections.abc import Callable, Iterable

from skidnav.errors import UserError
from skidnav.realtime.camera.calibration import FloorCalibration, calibrate, load_calibration
from skidnav.realtime.camera.intrinsics import (
    CameraIntrinsics,
    CharucoBoardSpec,
    calibrate_intrinsics,
    load_intrinsics,
)
from skidnav.realtime.camera.markers import ArenaLayout, MarkerDetector
from skidnav.realtime.camera.sources import Frame, FrameSource, open_frames
from skidnav.realtime.link.interface import Pose, RobotDriver

__all__ = [
    "ArenaLayout",
    "CameraIntrinsics",
    "CameraPoseSource",
    "CameraPosedDriver",
    "CharucoBoardSpec",
    "FloorCalibration",
    "Frame",
    "FrameSource",
    "MarkerDetector",
    "calibrate",
    "calibrate_intrinsics",
    "load_calibration",
    "load_intrinsics",
    "open_frames",
]

LOGGER = logging.getLogger(__name__)


class CameraPoseSource:
    """Latest robot pose seen by the overhead camera.

    A pose is *current* while the newest processed frame showed the robot marker and it was
    measured less than ``max_age`` seconds ago; otherwise :meth:`latest_pose` returns None, which
    the real-time loop treats as a lost pose (docs/realtime.md, "Safety": stop the wheels).

    Args:
        frames: the frames to read (a :class:`FrameSource` is closed by :meth:`close`).
        calibration: the floor calibration; its ``layout.robot_id`` is the marker tracked, and
            its lens model (if any) undistorts the marker's corners.
        max_age: how old [s] a pose may be before it counts as lost.
        clock: monotonic clock [s] used to stamp poses (the driver clock of ``Pose.stamp``).
        marker_height: height [m] of the robot marker above the corner-marker plane; a non-zero
            height is corrected for and needs a calibration made with intrinsics.

    Thread safety: :meth:`latest_pose` may be called from any thread while the background thread
    runs.
    """

    def __init__(
        self,
        frames: Iterable[Frame],
        calibration: FloorCalibration,
        *,
        max_age: float = 0.5,
        clock: Callable[[], float] = time.monotonic,
        marker_height: float = 0.0,
    ) -> None:
        if not max_age > 0:
            raise ValueError(f"expected max_age > 0 s, got {max_age}")
        if marker_height != 0.0:
            _check_marker_height(calibration, marker_height)
        self.calibration = calibration
        self.max_age = max_age
        self.marker_height = marker_height
        self.frames_processed = 0
        self.frames_with_robot = 0
        self.error: Exception | None = None
        self._frames = frames
        self._clock = clock
        self._detector = MarkerDetector(calibration.layout.dictionary)
        self._lock = threading.Lock()
        self._latest: Pose | None = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def process(self, frame: Frame) -> Pose | None:
        """Measure the robot pose in one frame and make it the latest (None if not visible).

        Raises:
            UserError: the frame's size differs from the calibration's image size.
        """
        stamp = self._clock()
        height, width = frame.image.shape[:2]
        if (width, height) != self.calibration.image_size:
            raise UserError(
                f"frame {frame.number} is {width}×{height} px but the calibration was made for "
                f"{self.calibration.image_size[0]}×{self.calibration.image_size[1]} px"
            )
        corners = self._detector.detect(frame.image).get(self.calibration.layout.robot_id)
        pose = None
        if corners is not None:
            x, y, heading = self.calibration.marker_pose(corners, self.marker_height)
            pose = Pose(stamp, x, y, heading)
        with self._lock:
            self._latest = pose
            self.frames_processed += 1
            self.frames_with_robot += pose is not None
        return pose

    def latest_pose(self) -> Pose | None:
        """The newest pose if the robot marker was in the newest frame and is fresh, else None."""
        with self._lock:
            pose = self._latest
        if pose is None or self._clock() - pose.stamp > self.max_age:
            return None
        return pose

    def start(self) -> None:
        """Read and process frames in a daemon thread until the source ends or :meth:`close`."""
        if self._thread is not None:
            raise RuntimeError("CameraPoseSource already started")
        self._thread = threading.Thread(target=self._run, name="skidnav-camera", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        try:
            for frame in self._frames:
                if self._stop.is_set():
                    break
                self.process(frame)
        except Exception as error:  # the loop sees the failure as a lost pose; keep the reason
            LOGGER.error("camera tracking stopped: %s", error)
            self.error = error
            with self._lock:
                self._latest = None

    def join(self, timeout: float | None = None) -> bool:
        """Wait for the background thread to finish; True if it has (or never started)."""
        if self._thread is not None:
            self._thread.join(timeout)
            return not self._thread.is_alive()
        return True

    @property
    def running(self) -> bool:
        """Whether the background thread is still reading frames."""
        return self._thread is not None and self._thread.is_alive()

    def close(self) -> None:
        """Stop the background thread and release the frame source (idempotent)."""
        self._stop.set()
        if not self.join(timeout=5.0):
            LOGGER.warning("camera thread did not stop within 5 s")
        if isinstance(self._frames, FrameSource):
            self._frames.close()

    def __enter__(self) -> CameraPoseSource:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()


def _check_marker_height(calibration: FloorCalibration, marker_height: float) -> None:
    """Raise ``ValueError`` unless ``calibration`` can correct for ``marker_height`` [m]."""
    if not math.isfinite(marker_height):
        raise ValueError(f"expected a finite marker height [m], got {marker_height}")
    pose = calibration.camera_pose
    if pose is None:
        raise ValueError("a marker height needs a floor calibration made with intrinsics")
    if not marker_height < pose.position[2]:
        raise ValueError(
            f"expected a marker height below the camera ({pose.position[2]:.3f} m up), "
            f"got {marker_height} m"
        )


class CameraPosedDriver:
    """A :class:`~skidnav.realtime.link.interface.RobotDriver` whose poses come from the
    overhead camera.

    Wheel commands, stop and the link go to ``driver`` (any RobotDriver); :meth:`latest_pose` is
    the camera's, so a robot without its own localisation (or with drifting odometry) can be used.

    Args:
        driver: the robot link (``sim``, ``tcp``, ``serial``, ``ros2``).
        camera: the pose source; :meth:`connect` starts its thread, :meth:`close` closes it.
    """

    def __init__(self, driver: RobotDriver, camera: CameraPoseSource) -> None:
        self.driver = driver
        self.camera = camera

    def connect(self) -> None:
        """Connect the robot, then start the camera thread."""
        self.driver.connect()
        if not self.camera.running:
            self.camera.start()

    def command(self, omega_left: float, omega_right: float) -> None:
        """Send wheel angular speeds [rad/s] to the robot."""
        self.driver.command(omega_left, omega_right)

    def latest_pose(self) -> Pose | None:
        """The camera's current pose (None when lost or stale)."""
        return self.camera.latest_pose()

    def stop(self) -> bool:
        """Stop the wheels through the robot link."""
        return self.driver.stop()

    def close(self) -> None:
        """Close the robot link (which stops the wheels), then the camera."""
        try:
            self.driver.close()
        finally:
            self.camera.close()
