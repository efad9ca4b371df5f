"""What makes an estimate good, bad or honest, on plain numbers: one copy for make eval (eval_recorder.py)
and make ablate (scripts/ablate). An estimate is "confidently wrong" when it is valid and off by more than
5 % of the true range or 10 deg (issue 11); it is honest on an axis when its error is within 3 sigma of its
own covariance."""
import math

WRONG_POSITION_FRACTION_OF_RANGE = 0.05
WRONG_ORIENTATION_DEG = 10.0
# Components whose variance is at least this are "not estimated" (TargetEstimate's convention).
NOT_ESTIMATED_VARIANCE = 1e6
AXES = ("x", "y", "z", "rx", "ry", "rz")


def quat_matrix(x, y, z, w):
    return [
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ]


def rotation_angle_deg(qa, qb):
    """Angle of the rotation between two orientations, each (x, y, z, w)."""
    dot = abs(sum(a * b for a, b in zip(qa, qb)))
    return math.degrees(2.0 * math.acos(min(1.0, dot)))


def rotation_error_vector(q_est, q_true):
    """dtheta with R_est = Exp(dtheta) * R_true (TargetEstimate's covariance convention: rotation about
    the camera's axes), rad; quaternions (x, y, z, w)."""
    re_, rt = quat_matrix(*q_est), quat_matrix(*q_true)
    d = [[sum(re_[i][k] * rt[j][k] for k in range(3)) for j in range(3)] for i in range(3)]  # R_est R_true^T
    cos_angle = max(-1.0, min(1.0, (d[0][0] + d[1][1] + d[2][2] - 1.0) / 2.0))
    angle = math.acos(cos_angle)
    axis = (d[2][1] - d[1][2], d[0][2] - d[2][0], d[1][0] - d[0][1])
    s = math.sin(angle)
    if s < 1e-9:
        return tuple(0.5 * a for a in axis)  # small angle: the skew part is the vector itself
    return tuple(angle * a / (2.0 * s) for a in axis)


def normalized_errors(position_error, rotation_error, variances):
    """Per axis (x, y, z, rx, ry, rz): error / sigma, None for an axis not claimed (rotation_error None, or a
    variance <= 0 or >= NOT_ESTIMATED_VARIANCE). variances: the pose covariance's diagonal."""
    errors = list(position_error) + (list(rotation_error) if rotation_error is not None else [None] * 3)
    return [None if (e is None or not (0.0 < v < NOT_ESTIMATED_VARIANCE)) else e / math.sqrt(v)
            for e, v in zip(errors, variances)]


def confidently_wrong(position_error_m, true_range_m, orientation_error_deg=None):
    """Valid and off by more than 5 % of the range, or (when it claims an orientation) by more than 10 deg."""
    return (position_error_m > WRONG_POSITION_FRACTION_OF_RANGE * true_range_m or
            (orientation_error_deg is not None and orientation_error_deg > WRONG_ORIENTATION_DEG))


def within_3_sigma(normalized_by_axis):
    """{axis: share of |error / sigma| <= 3} over the claimed axes (None: no estimate claims that axis)."""
    return {axis: (sum(1 for z in zs if abs(z) <= 3.0) / len(zs)) if zs else None
            for axis, zs in normalized_by_axis.items()}
