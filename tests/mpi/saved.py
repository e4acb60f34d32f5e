"""What the MPI check scripts save: of a solve its numbers and u_h at the nodes sorted by
coordinates (an order independent of the ranks); of a check its JSON report."""
import json

import numpy as np

from coupling.io.outputs import gather_p1


def save_solve(comm, path: str, result, **extra) -> None:
    """Gather u_h (collective) and, on rank 0, save the iterations, the energy, x and u
    sorted by coordinates, phi, ``converged`` and the ``extra`` arrays to the .npz at
    ``path``."""
    gathered = gather_p1(result.u)
    if comm.rank == 0:
        x, u, _ = gathered
        key = np.round(x, 12)  # exact ties despite 1e-18 noise in mesh coordinates
        order = np.lexsort((key[:, 1], key[:, 0]))
        np.savez(
            path,
            iterations=result.iterations,
            energy=result.energy,
            x=x[order],
            u=u[order],
            phi=result.phi,
            converged=result.converged,
            **extra,
        )


def save_json(comm, path: str, report) -> None:
    """Rank 0 of ``comm`` writes ``report`` as JSON to ``path``; not collective."""
    if comm.rank == 0:
        with open(path, "w") as fh:
            json.dump(report, fh)
