"""Galerkin BEM for the 2D Laplace operator (factor-2 convention of METHOD.md section 2)."""
from bem_cpp._bem import version

__all__ = ["version"]
