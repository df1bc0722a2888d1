"""Integer codes and constants shared by both kernel backends (no Numba here).

Contact states are mirrored in post.py and in the HDF5 attributes
(output-format.md): OPEN = 0, STICK = 1, SLIP = 2.
"""

OPEN = 0
STICK = 1
SLIP = 2

TANGENT_CONSISTENT = 0
TANGENT_SECANT = 1

# |Delta g_T| below this (m) has no usable secant; the elastic k_T is used.
SECANT_MIN_INCREMENT = 1.0e-300
