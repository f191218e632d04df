"""What an image's quality does to photogrammetry: laws from blur, ground sampling distance, incidence and texture.

Flat array-in / array-out functions (shapes broadcast); every law cites its source.

* **Feature scale and blur.** SIFT finds features from a base scale of sigma_0 = 1.6 px upwards (Lowe 2004,
  "Distinctive image features from scale-invariant keypoints", Sec. 3.3). A linear motion smear of length b px
  has the standard deviation b / sqrt(12) (a uniform distribution over the smear), which adds in quadrature to
  a feature's scale: s^2 = sigma_0^2 + b^2 / 12. Two consequences:

  - the localisation noise of a matched feature grows with its scale (Foerstner & Guelch 1987: the precision
    of a point is proportional to the width of the feature it is found on): sigma_px(b) = sigma_px(0) * s /
    sigma_0;
  - the density of features falls like 1 / s^2 (in a self-similar texture the number of blobs per image area
    at scale s goes like s^-2), so the usable keypoints keep the fraction sigma_0^2 / s^2.

  Both change gradually: 5 px of blur keeps 55 % of the keypoints at 1.35 x the noise, 25 px 5 % at 4.6 x.
  Blur below half a pixel (the practitioners' half-pixel rule, e.g. ArduPilot Mission Planner's camera
  calculator, issue 1601) costs under 1 % of the keypoints and 0.4 % of the precision. Sieberth, Wackrow &
  Chandler 2016 (ISPRS J. Photogramm. 122) find that motion blur degrades, and past some point prevents,
  automatic photogrammetric processing; this law degrades, and lets a heavily blurred view drop out because it
  no longer has enough keypoints to register (the registration threshold), rather than at a fixed blur cliff.
* **GSD and texture.** The surface has structure down to a scale ``texture_m`` (paint grain, rust, welds). A
  feature of image scale sigma_0 spans sigma_0 * GSD metres on the surface; where that is finer than the
  texture (close views), the texture cannot fill the image with features: the density keeps the fraction
  min(1, (sigma_0 GSD / texture_m)^2) (same self-similarity argument, on the surface side).
* **Dense matching.** Multi-view stereo matches windows of pixels (COLMAP PatchMatchStereo: 11 x 11 px), not
  only keypoints: a surface patch is found in a view with probability 1 - exp(-W), W the number of its
  independent windows of usable texture (patch pixels x keypoint fraction / 121). A ship patch at the
  paper's standoffs covers thousands of pixels, so blur costs dense points only when it is extreme, while it
  costs keypoints (registration, pose) and precision (noise) directly.
* **Image border.** A descriptor needs its support window inside the image (SIFT: 16 x 16 cells of the
  keypoint's scale; COLMAP/VLFeat drop keypoints whose window leaves the image), so observations fade out over
  the last ``BORDER_FRACTION`` of the image width.
* **Incidence and parallax.** Hard limits become linear-in-cosine / linear ramps of a few degrees around the
  configured limits (the limits keep their meaning as the 50 % points): matching beyond ~60 deg of viewpoint
  change and beyond ~80 deg of incidence fails gradually, not at a line.
"""

from __future__ import annotations

import numpy as np

SIFT_BASE_SCALE_PX = 1.6       # Lowe 2004, Sec. 3.3
BORDER_FRACTION = 0.02         # of the image width: a descriptor window at the keypoint scales that matter
INCIDENCE_RAMP_DEG = 5.0       # half width of the incidence ramp around oracle.synthetic.incidence_max_deg
PARALLAX_MIN_RAMP_DEG = 2.5    # half width of the triangulation ramp around parallax_min_deg
PARALLAX_MAX_RAMP_DEG = 5.0    # half width of the matching ramp around parallax_max_deg
MVS_WINDOW_PX2 = 11 * 11       # COLMAP PatchMatchStereo's default window (window_radius 5)


def ramp(x: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """0 below ``lo``, 1 above ``hi``, linear between (same shape as x)."""
    return np.clip((np.asarray(x, dtype=float) - lo) / (hi - lo), 0.0, 1.0)


def feature_scale_px(blur_px: np.ndarray) -> np.ndarray:
    """Scale (px) of the finest usable feature in an image smeared by ``blur_px``: sqrt(sigma_0^2 + b^2 / 12)."""
    b = np.asarray(blur_px, dtype=float)
    return np.sqrt(SIFT_BASE_SCALE_PX ** 2 + b * b / 12.0)


def pixel_noise_px(sigma_px: float, blur_px: np.ndarray) -> np.ndarray:
    """Matching noise (px) of a feature in a blurred image: ``sigma_px`` x (feature scale / sigma_0)."""
    return sigma_px * feature_scale_px(blur_px) / SIFT_BASE_SCALE_PX


def blur_keypoint_fraction(blur_px: np.ndarray) -> np.ndarray:
    """Fraction (0..1] of its sharp keypoints an image smeared by ``blur_px`` keeps: (sigma_0 / scale)^2."""
    return (SIFT_BASE_SCALE_PX / feature_scale_px(blur_px)) ** 2


def texture_keypoint_fraction(gsd_m: np.ndarray, texture_m: float) -> np.ndarray:
    """Fraction (0..1] of a fully textured image's keypoints on a surface textured down to ``texture_m``,
    seen at ``gsd_m`` (m/px): min(1, (sigma_0 GSD / texture_m)^2)."""
    return np.minimum(1.0, (SIFT_BASE_SCALE_PX * np.asarray(gsd_m, dtype=float) / texture_m) ** 2)


def keypoint_fraction(blur_px: np.ndarray, gsd_m: np.ndarray, texture_m: float) -> np.ndarray:
    """Fraction (0..1] of a sharp, fully textured image's keypoints that a view keeps: the blur law times the
    texture law (module docstring). blur_px and gsd_m (m/px) broadcast."""
    return blur_keypoint_fraction(blur_px) * texture_keypoint_fraction(gsd_m, texture_m)


def patch_match_probability(textured_px2: np.ndarray) -> np.ndarray:
    """0..1: the probability that dense matching finds a surface patch whose image covers ``textured_px2``
    pixels of usable texture (its area x the keypoint fraction): 1 - exp(-independent matching windows)."""
    return -np.expm1(-np.asarray(textured_px2, dtype=float) / MVS_WINDOW_PX2)


def border_weight(u: np.ndarray, v: np.ndarray, width_px: float, height_px: float) -> np.ndarray:
    """0..1: how far inside the image a pixel (u, v) lies, ramping over ``BORDER_FRACTION`` of the width."""
    margin = np.minimum(np.minimum(u, width_px - u), np.minimum(v, height_px - v))
    return ramp(margin, 0.0, BORDER_FRACTION * width_px)


def incidence_weight(cos_incidence: np.ndarray, incidence_max_rad: float) -> np.ndarray:
    """0..1: matchability at an incidence angle, ramping in cosine over +-INCIDENCE_RAMP_DEG around the limit."""
    h = np.radians(INCIDENCE_RAMP_DEG)
    return ramp(cos_incidence, np.cos(incidence_max_rad + h), np.cos(incidence_max_rad - h))


def parallax_weights(alpha_rad: np.ndarray, parallax_min_rad: float,
                     parallax_max_rad: float) -> tuple[np.ndarray, np.ndarray]:
    """(matchable, triangulates) 0..1 of view pairs whose rays to a point differ by ``alpha_rad``: matching
    fades out around ``parallax_max``, triangulation fades in around ``parallax_min`` (ramps in degrees)."""
    lo, hi = np.radians(PARALLAX_MIN_RAMP_DEG), np.radians(PARALLAX_MAX_RAMP_DEG)
    matchable = 1.0 - ramp(alpha_rad, parallax_max_rad - hi, parallax_max_rad + hi)
    return matchable, matchable * ramp(alpha_rad, parallax_min_rad - lo, parallax_min_rad + lo)
