"""Outputs of a run: atomic files, summary.json / fields.npz / XDMF, plots."""
