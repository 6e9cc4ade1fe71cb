"""Type stub of the dynahand extension module (python/module.cpp and python/bind_*.cpp;
docs/python.md).

Metres, camera frame as OpenCV (x right, y down, z forward); keypoints in MediaPipe order.
"""

import os
from typing import Iterable, Iterator, Optional, Sequence as _Seq, Tuple, TypedDict, Union

import numpy as np
import numpy.typing as npt

__version__: str

_F32 = npt.NDArray[np.float32]
_U16 = npt.NDArray[np.uint16]
_Path = Union[str, "os.PathLike[str]"]
_CameraLike = Union["Camera", dict, "Sequence", "SyntheticClip"]
_Frame = Tuple[_U16, float, Optional[_F32]]
_KeypointsLike = Union[npt.ArrayLike, _Seq[Optional[npt.ArrayLike]]]
# Frames a hand size is estimated from: a Sequence, a SyntheticClip, an (N, H, W) uint16 array,
# or an iterable of (H, W) uint16 arrays or (depth, depth_scale, ...) tuples.
_FramesLike = Union["Sequence", "SyntheticClip", _U16, Iterable[Union[_U16, tuple]]]

class Camera:
    """Pinhole depth camera intrinsics (pixels)."""

    def __init__(
        self, width: int, height: int, fx: float, fy: float, cx: float, cy: float
    ) -> None: ...
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def fx(self) -> float: ...
    @property
    def fy(self) -> float: ...
    @property
    def cx(self) -> float: ...
    @property
    def cy(self) -> float: ...
    def to_dict(self) -> dict: ...

class HandResult:
    """One hand's result for one frame; arrays float32, metres, NaN when not tracked."""

    @property
    def side(self) -> str: ...
    @property
    def tracked(self) -> bool: ...
    @property
    def keypoints21(self) -> _F32:
        """(21, 3) keypoints, MediaPipe order: the pose's moved toward the detector's."""
    @property
    def skeleton_keypoints21(self) -> _F32:
        """(21, 3) the pose's own keypoints, MediaPipe order."""
    @property
    def openxr26(self) -> _F32:
        """(26, 8): x, y, z, qw, qx, qy, qz, radius per OpenXR joint."""
    @property
    def bodies(self) -> _F32:
        """(17, 7): x, y, z, qw, qx, qy, qz per model body (Tracker.body_names)."""
    @property
    def error(self) -> float: ...
    @property
    def fit_error(self) -> float: ...
    @property
    def occlusion_error(self) -> float: ...
    @property
    def body_error(self) -> _F32: ...
    @property
    def simulation(self) -> str: ...
    @property
    def acquired(self) -> bool: ...
    @property
    def points(self) -> int: ...
    @property
    def data_near_model(self) -> float: ...
    @property
    def model_on_hand(self) -> float: ...
    @property
    def fingertips_off_hand(self) -> int: ...
    @property
    def detected(self) -> bool: ...
    @property
    def detector_keypoints21(self) -> _F32: ...
    @property
    def detector_confidence(self) -> _F32: ...
    @property
    def detector_disagreement(self) -> float: ...
    @property
    def disagreeing_frames(self) -> int: ...

class HandSize:
    """A hand size estimated from depth frames (estimate_hand_size, Tracker(hand_size="auto")).
    Made by those only; pass it to Tracker as hand_size."""

    @property
    def length(self) -> float:
        """Wrist crease to middle fingertip, m."""
    @property
    def width(self) -> float:
        """Palm width across the knuckles, m."""
    @property
    def fit_score(self) -> float:
        """The best candidate's fit in [0, 1] (about 0.98-0.99 on clean synthetic data)."""
    @property
    def frames_used(self) -> int: ...
    @property
    def candidates(self) -> int:
        """Candidate models tracked (13 for the size, 7 with a length or width given; up to 24
        more for the metacarpals)."""
    @property
    def metacarpals(self) -> tuple[float, float, float, float, float]:
        """Each digit's metacarpal length factor, thumb to pinky (1: the built-in hand's; all 1
        when no frame showed the palm to the camera)."""
    def to_dict(self) -> dict: ...

class Tracker:
    """Tracks one or two hands in depth frames, as `dynahand track` does."""

    openxr_joint_names: list[str]
    def __init__(
        self,
        camera: _CameraLike,
        hands: int = 1,
        hand_size: Union[None, Tuple[float, float], str, HandSize] = None,
        detector: Union[bool, _Path] = True,
        threads: int = 1,
        per_frame: bool = False,
        fps: Optional[float] = None,
        model_file: Optional[_Path] = None,
        frames: Optional[_FramesLike] = None,
        hand_size_frames: int = 30,
        behind_user: bool = False,
        settings: Optional[dict[str, Union[float, int, bool]]] = None,
    ) -> None:
        """settings: tracker settings by the names `dynahand settings` lists
        ({"detector.selectionWeight": 0}), as `dynahand track --set` takes them.
        hand_size: None (0.19, 0.085), (length, width) in m, a HandSize
        (estimate_hand_size()), or "auto": estimated as `dynahand track --hand-size auto` from
        the first hand_size_frames (10..600) frames of `frames` (default: camera, when it is a
        Sequence or SyntheticClip) before anything is tracked; track() then starts at frame 0.
        ValueError for "auto" without frames, frames without "auto", or too few frames."""
    def track(
        self, depth: _U16, depth_scale: float = 0.001, timestamp: Optional[float] = None
    ) -> list[HandResult]:
        """Tracks one (H, W) uint16 frame; one HandResult per hand."""
    def initialize(self, keypoints21: npt.ArrayLike, side: str = "right") -> None: ...
    def reset(self) -> None: ...
    def result_json(self) -> str:
        """The last frame as the JSON line `dynahand track --out` writes."""
    @property
    def camera(self) -> Camera: ...
    @property
    def fps(self) -> float: ...
    @property
    def frames(self) -> int: ...
    @property
    def hands(self) -> int: ...
    @property
    def hand_size(self) -> Optional[Tuple[float, float]]: ...
    @property
    def hand_size_estimate(self) -> Optional[HandSize]:
        """The HandSize the hand was built from ("auto" or a HandSize); else None."""
    @property
    def detector(self) -> bool: ...
    @property
    def detector_weights(self) -> str: ...
    @property
    def body_names(self) -> list[str]: ...

def estimate_hand_size(
    frames: _FramesLike,
    camera: Optional[_CameraLike] = None,
    start_keypoints: Optional[npt.ArrayLike] = None,
    frames_used: int = 30,
    threads: int = 1,
    length: Optional[float] = None,
    width: Optional[float] = None,
    hands: int = 1,
    per_frame: bool = False,
    depth_scale: float = 0.001,
    fps: Optional[float] = None,
    metacarpals: bool = True,
) -> HandSize:
    """The built-in hand's size from the first frames_used (10..600) frames, as
    `dynahand track --hand-size auto` estimates it, and each digit's metacarpal length
    (metacarpals=False: the size alone, as --hand-size-only). camera defaults to the frames' own;
    start_keypoints as --init gt; a given length or width is kept. Frame i is at i / fps s;
    bare arrays at depth_scale. Reads no further than frames_used items. ValueError for bad
    arguments or too few frames (more than 6 without start_keypoints), OSError for a frame
    that cannot be read."""

class SequenceIterator:
    def __iter__(self) -> SequenceIterator: ...
    def __next__(self) -> _Frame: ...

class Sequence:
    """A depth recording: frames (depth, depth_scale, ground_truth or None)."""

    def __len__(self) -> int: ...
    def __getitem__(self, index: int) -> _Frame: ...
    def __iter__(self) -> SequenceIterator: ...
    def frame(self, index: int) -> _Frame: ...
    def ground_truth(self, index: int) -> Optional[_F32]: ...
    def ground_truth_array(self) -> _F32: ...
    @property
    def camera(self) -> Camera: ...
    @property
    def fps(self) -> float: ...
    @property
    def depth_scale(self) -> float: ...
    @property
    def min_range_m(self) -> float:
        """The camera's near range, m (nothing nearer is measured); 0 = not recorded."""
    @property
    def format(self) -> str: ...
    @property
    def has_ground_truth(self) -> bool: ...
    @property
    def path(self) -> str: ...
    @property
    def info(self) -> dict: ...

def open_sequence(
    path: _Path, camera: Optional[_CameraLike] = None, depth_scale: Optional[float] = None
) -> Sequence:
    """Opens any recording `dynahand track` reads (FileNotFoundError / OSError on failure)."""

class SyntheticClipIterator:
    def __iter__(self) -> SyntheticClipIterator: ...
    def __next__(self) -> Tuple[_U16, float, _F32]: ...

class SyntheticClip:
    """A synthetic clip rendered on demand, with exact ground truth."""

    def __len__(self) -> int: ...
    def __getitem__(self, index: int) -> Tuple[_U16, float, _F32]: ...
    def __iter__(self) -> SyntheticClipIterator: ...
    def frame(self, index: int) -> Tuple[_U16, float, _F32]: ...
    def ground_truth(self, index: int, hand: int = 0) -> _F32: ...
    def pose(self, index: int, hand: int = 0) -> _F32: ...
    def arrays(self) -> Tuple[_U16, _F32]:
        """(depth (N, H, W) uint16, ground truth (N, 21, 3) float32)."""
    @property
    def camera(self) -> Camera: ...
    @property
    def fps(self) -> float: ...
    @property
    def hand_count(self) -> int: ...
    @property
    def motion(self) -> str: ...
    @property
    def profile(self) -> str: ...
    @property
    def min_range_m(self) -> float:
        """The sensor profile's near range, m (nothing nearer is measured)."""

def synth(
    motion: str = "wave",
    frames: int = 300,
    profile: str = "tof",
    placement: str = "desk",
    seed: int = 1,
    fps: float = 30.0,
    speed: float = 1.0,
    background: str = "none",
    table: bool = False,
    hand_size: Optional[Tuple[float, float]] = None,
    proportion_spread: float = 0.0,
    proportion_seed: int = 1,
    held_object: str = "none",
    held_object_size: float = 0.025,
) -> SyntheticClip:
    """A synthetic clip in memory, as `dynahand synth` renders it (held_object: none, ball,
    cylinder or box against the palm; held_object_size: its radius or half-thickness, m)."""

def clips() -> list[str]: ...

class Metrics:
    """The figures `dynahand eval` prints (mm, s)."""

    frames: int
    visible_frames: int
    evaluated_frames: int
    mean_mm: float
    median_mm: float
    p95_mm: float
    max_mm: float
    jitter_mm: float
    lost_frames: int
    lost_episodes: int
    mean_recovery_s: float
    max_recovery_s: float
    unrecovered_episodes: int
    @property
    def success_thresholds_mm(self) -> npt.NDArray[np.float64]: ...
    @property
    def success_fraction(self) -> npt.NDArray[np.float64]: ...
    @property
    def per_joint_mean_mm(self) -> npt.NDArray[np.float64]: ...
    @property
    def per_frame_mean_mm(self) -> npt.NDArray[np.float64]: ...
    @property
    def per_frame_max_mm(self) -> npt.NDArray[np.float64]: ...
    def summary(self) -> str: ...
    def report_markdown(self, title: str = "Evaluation") -> str: ...

def evaluate(
    gt: _KeypointsLike, pred: _KeypointsLike, fps: float = 30.0, lost_mm: float = 50.0
) -> Metrics:
    """Accuracy of pred against gt, as `dynahand eval`."""

class _DetectorData(TypedDict):  # a plain dict at run time
    pixels: npt.NDArray[np.uint8]  # (N, 64, 64): x in [-1, 1] is pixels / 127.5 - 1
    uvd: _F32  # (N, 21, 3): keypoints in normalised crop coordinates
    profile: npt.NDArray[np.int32]  # (N,): sensor profile index
    source: npt.NDArray[np.int32]  # (N,): 0 random pose, 1 clip pose, 2 perturbed clip pose

def detector_data(
    split: str = "train",
    count: int = 1000,
    seed: int = 1,
    threads: int = 1,
    proportion_spread: float = 0.15,
    held_object_share: float = 0.15,
    held_object_boxes: bool = False,
    shared_curl_share: float = 0.3,
) -> _DetectorData:
    """The detector's synthetic training samples, value for value those
    `dynahand detector data --split S --count N --seed SEED` writes (split: "train" or
    "held-back"; the same for any threads)."""
