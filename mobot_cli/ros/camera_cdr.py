"""CDR bytes of a camera's messages: sensor_msgs/Image and sensor_msgs/CameraInfo (docs/cameras.md).

Image: rgb8, bgr8 or mono8 as the camera's encoding; depth as 32FC1 (float32 metres, +inf
beyond the far clip, REP 117), as gazebo_ros_camera and ros_gz_bridge publish them; little
endian, rows packed (``step`` = width x bytes per pixel). CameraInfo: plumb_bob with no
distortion, K = [fx 0 cx; 0 fy cy; 0 0 1], R = I, P = [K | 0], as the ideal pinhole the renderer
draws (sim/sensing/render.py). The bag and the ROS 2 publisher send the same bytes.

CompressedImage (the bag's images with ``log.images`` png or jpeg): what image_transport's
compressed plugin publishes on ``image_raw/compressed``: ``format`` "<encoding>; png compressed
bgr8" (mono8 for a grey camera, as its publisher names the target), ``data`` a whole PNG or JPEG
file of the image (Pillow; JPEG at quality 95, the plugin's default; PNG at zlib level 6).
Depth images stay raw 32FC1.
"""

from __future__ import annotations

import numpy as np

from mobot_cli.plan import SensorSpec
from mobot_cli.ros.sensor_cdr import CdrWriter
from mobot_cli.sim.sensing.render import intrinsics

DEPTH_ENCODING = "32FC1"
COMPRESSIONS = ("png", "jpeg")
JPEG_QUALITY = 95  # compressed_image_transport's jpeg_quality default
PNG_LEVEL = 6  # zlib level (Pillow's default; the plugin's png_level 9 costs far more for little)


def image(stamp: tuple[int, int], frame_id: str, pixels: np.ndarray, encoding: str) -> bytes:
    """sensor_msgs/Image of uint8 (H, W[, 3]) pixels, or float32 (H, W) depth as 32FC1."""
    array = np.ascontiguousarray(pixels, dtype="<f4" if encoding == DEPTH_ENCODING else np.uint8)
    height, width = array.shape[:2]
    w = CdrWriter().header(stamp, frame_id).pack("II", height, width).string(encoding)
    w.pack("B", 0).u32(array.nbytes // max(1, height))
    w.u32(array.nbytes)
    return w.put(array.tobytes(), 1).bytes()


def compressed(stamp: tuple[int, int], frame_id: str, pixels: np.ndarray, encoding: str, compression: str) -> bytes:
    """sensor_msgs/CompressedImage of uint8 pixels in ``encoding``, as a PNG or JPEG file."""
    import io

    from PIL import Image

    array = np.ascontiguousarray(pixels[:, :, ::-1] if encoding == "bgr8" else pixels, dtype=np.uint8)
    buffer = io.BytesIO()
    picture = Image.fromarray(array, "L" if array.ndim == 2 else "RGB")
    if compression == "jpeg":
        picture.save(buffer, "JPEG", quality=JPEG_QUALITY)
    else:
        picture.save(buffer, "PNG", compress_level=PNG_LEVEL)
    target = "mono8" if encoding == "mono8" else "bgr8"
    data = buffer.getvalue()
    w = CdrWriter().header(stamp, frame_id).string(f"{encoding}; {compression} compressed {target}")
    return w.u32(len(data)).put(data, 1).bytes()


def camera_info(stamp: tuple[int, int], frame_id: str, spec: SensorSpec) -> bytes:
    """sensor_msgs/CameraInfo of the camera's ideal pinhole."""
    fx, fy, cx, cy = intrinsics(spec)
    w = CdrWriter().header(stamp, frame_id).pack("II", spec.height, spec.width).string("plumb_bob")
    w.u32(5).pack("5d", *(0.0,) * 5)
    w.pack("9d", fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0)
    w.pack("9d", 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)
    w.pack("12d", fx, 0.0, cx, 0.0, 0.0, fy, cy, 0.0, 0.0, 0.0, 1.0, 0.0)
    w.pack("II", 0, 0)  # binning
    return w.pack("4I", 0, 0, 0, 0).pack("B", 0).bytes()  # roi: the whole image, no rectification


def messages(stamp: tuple[int, int], frame_id: str, spec: SensorSpec, data, topics: dict[str, str],
             compression: str = "raw") -> list[tuple[str, bytes]]:
    """(topic, CDR bytes) of one ImageData: image, depth and camera info, each where the camera has it;
    the image as a CompressedImage with ``compression`` png or jpeg."""
    rgb, depth = data.rgb, data.depth
    if rgb is None and depth is None:
        return []
    out = []
    if rgb is not None:
        out.append((topics["image"], compressed(stamp, frame_id, rgb, spec.encoding, compression)
                    if compression in COMPRESSIONS else image(stamp, frame_id, rgb, spec.encoding)))
    if depth is not None:
        out.append((topics["depth"], image(stamp, frame_id, depth, DEPTH_ENCODING)))
    out.append((topics["camera_info"], camera_info(stamp, frame_id, spec)))
    return out
