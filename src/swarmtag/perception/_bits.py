"""A second read of the candidates OpenCV rejected: their bits, sampled at sub-pixel corners.

``cv2.aruco.ArucoDetector`` reads a candidate's bits *before* it refines the
corners: it warps the image through the integer-pixel polygon of the candidate's
contour (``approxPolyDP``) and thresholds each cell. For a small marker seen at
a slant that polygon is off by up to 2 px, nearly a whole module when a module
is 2-2.5 px (a carrier at 2 m turned 30-45 degrees), so the cells are read from
their neighbours and a perfectly readable marker is rejected (docs/perception.md:
three of the four misses inside the old reliable range). ``read_candidate``
reads such a candidate again: it refines the corners first (``cornerSubPix``
with the detector's own window: one module, at most ``cornerRefinementWinSize``),
then samples each cell's central half with bilinear interpolation, and accepts
the candidate only under the detector's own rules: the Otsu threshold and its
``minOtsuStdDev``, at most ``maxErroneousBitsInBorderRate`` of the border
wrong, and ``Dictionary.identify`` with the detector's ``errorCorrectionRate``.
Only where the bits are read changes, not how strict the acceptance is.
"""

from __future__ import annotations

from typing import Any, Final

import numpy as np
from numpy.typing import NDArray

from swarmtag.perception._opencv import opencv

__all__ = ["SAMPLES_PER_MODULE", "read_candidate"]

Float = NDArray[np.float64]

SAMPLES_PER_MODULE: Final = 8
"""Samples per module side in the rectified marker (bilinear interpolation)."""
CELL_CORE: Final = 0.5
"""Share of a cell's side, centred, whose samples give the cell's value (away from its edges,
which blur into the neighbours)."""


def _refine(gray: NDArray[np.uint8], quad: Float, modules: int, parameters: Any) -> Float:  # noqa: ANN401
    """The quad's corners refined to sub-pixel precision, as the detector refines a marker's."""
    cv2 = opencv()
    sides = np.linalg.norm(quad - np.roll(quad, -1, axis=0), axis=1)
    module = float(sides.mean()) / modules
    window = round(float(parameters.relativeCornerRefinmentWinSize) * module)
    window = max(1, min(window, int(parameters.cornerRefinementWinSize)))
    criteria = (
        cv2.TERM_CRITERIA_MAX_ITER | cv2.TERM_CRITERIA_EPS,
        int(parameters.cornerRefinementMaxIterations),
        float(parameters.cornerRefinementMinAccuracy),
    )
    points = np.ascontiguousarray(quad, dtype=np.float32).reshape(-1, 1, 2)
    refined = cv2.cornerSubPix(gray, points, (window, window), (-1, -1), criteria)
    return np.asarray(refined, dtype=np.float64).reshape(4, 2)


def _cells(gray: NDArray[np.uint8], corners: Float, modules: int) -> Float:
    """Mean grey level of each cell's central part, (modules, modules), border included."""
    cv2 = opencv()
    size = modules * SAMPLES_PER_MODULE
    edge = size - 0.5  # the black square's outer corners lie on the samples' outer edges
    target = np.array([[-0.5, -0.5], [edge, -0.5], [edge, edge], [-0.5, edge]], dtype=np.float32)
    transform = cv2.getPerspectiveTransform(corners.astype(np.float32), target)
    flat = cv2.warpPerspective(gray, transform, (size, size), flags=cv2.INTER_LINEAR)
    margin = round((1.0 - CELL_CORE) / 2 * SAMPLES_PER_MODULE)
    core = np.asarray(flat, dtype=np.float64).reshape(
        modules, SAMPLES_PER_MODULE, modules, SAMPLES_PER_MODULE
    )[:, margin : SAMPLES_PER_MODULE - margin, :, margin : SAMPLES_PER_MODULE - margin]
    cells: Float = core.mean(axis=(1, 3))
    return cells


def read_candidate(gray: NDArray[np.uint8], quad: Float, detector: Any) -> tuple[int, Float] | None:  # noqa: ANN401
    """The marker id and corners (4, 2; OpenCV's order) of a rejected candidate, or None.

    ``quad`` (4, 2): the candidate's corners as ``detectMarkers`` rejected them
    (clockwise in the image); ``detector``: the ``cv2.aruco.ArucoDetector`` whose
    dictionary and acceptance rules apply.
    """
    cv2 = opencv()
    dictionary = detector.getDictionary()
    parameters = detector.getDetectorParameters()
    border = int(parameters.markerBorderBits)
    bits = int(dictionary.markerSize)
    modules = bits + 2 * border
    corners = _refine(gray, quad, modules, parameters)
    if not np.all(np.isfinite(corners)):
        return None
    cells = _cells(gray, corners, modules)
    levels = np.clip(np.rint(cells), 0, 255).astype(np.uint8)
    if float(cells[border:-border, border:-border].std()) < float(parameters.minOtsuStdDev):
        return None  # all one shade: no code to read (OpenCV's own test, on the inner cells)
    _, binary = cv2.threshold(levels, 0, 1, cv2.THRESH_BINARY | cv2.THRESH_OTSU)
    white = np.asarray(binary, dtype=np.uint8)  # Otsu's split of the cells' levels
    ring = np.ones((modules, modules), dtype=bool)
    ring[border:-border, border:-border] = False
    if int(white[ring].sum()) > int(bits * bits * float(parameters.maxErroneousBitsInBorderRate)):
        return None
    inner = np.ascontiguousarray(white[border:-border, border:-border])
    found, marker, rotation = dictionary.identify(inner, float(parameters.errorCorrectionRate))
    if not found:
        return None
    return int(marker), np.roll(corners, int(rotation), axis=0)
