"""The mass-spring demos moved to :mod:`particles.demos.massspring`; this name is kept for old imports."""

from .demos.massspring import draped_cloth, hanging_cloth

__all__ = ["hanging_cloth", "draped_cloth"]
