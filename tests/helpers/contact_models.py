"""Small model configs (mappings for fivid.fe.load_model) of the contact-law tests. Synthetic geometry.

The benchmark models live once, with the verification cases that use them (fivid/verify/models.py)."""

from fivid.verify.models import block_on_belt, block_on_line, ring_on_shaft, roller_on_flat

__all__ = ["block_on_belt", "block_on_line", "ring_on_shaft", "roller_on_flat"]
