"""fem_py.partition.Ragged (the coarse-edge chains as one flat array + offsets) against a
tuple-of-arrays reference, the pack/unpack round trip of CoarseStructure, and the
sorting helpers of _coarse_from_skeleton against the NumPy calls they replace.

Everything here is integer bookkeeping or copies of floats: equality is exact."""
import pickle

import numpy as np
import pytest
from mpi4py import MPI

from fem_py.partition import CoarseStructure, Ragged, as_ragged
from fem_py.partition.coarse import _first_index, _pack, _sort_rows, _unpack

LENGTHS = [3, 0, 5, 3, 1, 5, 2, 3]


def _reference(trailing=()):
    rng = np.random.default_rng(7)
    return tuple(rng.integers(-50, 50, size=(m,) + trailing).astype(np.int64) for m in LENGTHS)


def _same(a, b):
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and np.array_equal(a, b)


@pytest.mark.parametrize("trailing", [(), (2,)])
def test_sequence_behaviour_matches_tuple(trailing):
    ref = _reference(trailing)
    r = as_ragged(ref)
    assert len(r) == len(ref)
    assert r.flat.shape == (sum(LENGTHS),) + trailing
    assert _same(r.lengths, np.array(LENGTHS))
    assert _same(r.offsets, np.concatenate([[0], np.cumsum(LENGTHS)]))
    for k in range(-len(ref), len(ref)):
        assert _same(r[k], ref[k])
        assert np.shares_memory(r[k], r.flat) or len(r[k]) == 0  # a view, not a copy
    assert _same(r[np.int64(2)], ref[2])
    for bad in (len(ref), -len(ref) - 1):
        with pytest.raises(IndexError):
            r[bad]
    assert all(_same(a, b) for a, b in zip(r, ref))
    assert len(list(r)) == len(ref)
    assert _same(np.concatenate(r), np.concatenate(ref))
    for sl in (
        slice(1, None),
        slice(None, -2),
        slice(2, 6),
        slice(None, None, 2),
        slice(None, None, -1),
        slice(5, 2),
        slice(-3, None, -2),
        slice(0, 0),
    ):
        sub = r[sl]
        assert isinstance(sub, Ragged)
        assert len(sub) == len(ref[sl])
        assert all(_same(a, b) for a, b in zip(sub, ref[sl]))


def test_concatenation_with_tuples():
    ref = _reference()
    r = as_ragged(ref)
    first = ref[0][::-1]
    left = (first,) + r[1:]
    right = r[:-1] + (ref[-1][::-1],)
    assert isinstance(left, Ragged) and isinstance(right, Ragged)
    assert all(_same(a, b) for a, b in zip(left, (first,) + ref[1:]))
    assert all(_same(a, b) for a, b in zip(right, ref[:-1] + (ref[-1][::-1],)))
    assert all(_same(a, b) for a, b in zip(r + r, ref + ref))


def test_rows_and_groups_match_stack():
    ref = _reference((2,))
    r = as_ragged(ref)
    lengths = np.array(LENGTHS)
    groups = r.length_groups()
    assert [g[0] for g in groups] == np.unique(lengths).tolist()
    for length, group in groups:
        assert _same(group, np.flatnonzero(lengths == length))
        assert _same(r.rows(group), np.stack([ref[k] for k in group]))
    assert r.rows([]).shape == (0, 0, 2)
    with pytest.raises(ValueError, match="equal length"):
        r.rows([0, 2])


def test_take_matches_tuple():
    ref = _reference()
    r = as_ragged(ref)
    idx = np.array([7, 1, 2, 2, -1, 0])
    assert all(_same(a, ref[k]) for a, k in zip(r.take(idx), idx))
    with pytest.raises(IndexError):
        r.take([len(ref)])


def test_read_only_and_immutable():
    r = as_ragged(_reference())
    with pytest.raises(ValueError):
        r[0][0] = 1
    with pytest.raises(ValueError):
        r.flat[0] = 1
    with pytest.raises(AttributeError):
        r.flat = np.zeros(3)
    src = np.arange(6)
    Ragged(src, [0, 2, 6])
    src[0] = 5  # the caller's array stays writable


def test_as_ragged_and_validation():
    r = as_ragged(_reference())
    assert as_ragged(r) is r
    assert as_ragged(r, dtype=np.int64) is r
    assert as_ragged(r, dtype=np.int32).flat.dtype == np.int32
    empty = as_ragged((), item_shape=(2,))
    assert len(empty) == 0 and empty.flat.shape == (0, 2)
    with pytest.raises(ValueError, match="trailing shapes"):
        as_ragged([np.zeros(3), np.zeros((3, 2))])
    with pytest.raises(ValueError, match="offsets"):
        Ragged(np.arange(5), [0, 3, 4])
    with pytest.raises(ValueError, match="offsets"):
        Ragged(np.arange(5), [0, 3, 2, 5])
    copy = pickle.loads(pickle.dumps(r))
    assert isinstance(copy, Ragged) and all(_same(a, b) for a, b in zip(copy, r))


def test_sort_rows_equals_lexsort():
    rng = np.random.default_rng(3)
    lengths = rng.integers(0, 7, size=200)
    offsets = np.concatenate([[0], np.cumsum(lengths)])
    values = rng.permutation(offsets[-1])
    key = rng.integers(0, 3, size=offsets[-1]).astype(float)  # many ties: stability matters
    row = np.repeat(np.arange(len(lengths)), lengths)
    got = _sort_rows(Ragged(values, offsets), key)
    assert _same(got.flat, values[np.lexsort((key, row))])
    assert _same(got.offsets, offsets)


@pytest.mark.parametrize("shuffle", [False, True])
def test_first_index_equals_minimum_at(shuffle):
    rng = np.random.default_rng(5)
    labels = np.repeat(np.arange(40), rng.integers(1, 5, size=40))
    rng.shuffle(labels)
    if not shuffle:  # relabel in order of first appearance, as connected_components does
        _, first = np.unique(labels, return_index=True)
        rank = np.empty(40, dtype=np.int64)
        rank[np.argsort(first)] = np.arange(40)
        labels = rank[labels]
    reference = np.full(40, len(labels))
    np.minimum.at(reference, labels, np.arange(len(labels)))
    assert np.array_equal(_first_index(labels, 40), reference)


def test_pack_unpack_round_trip():
    from fem_py.mesh import GeometrySpec, build_domain

    c = build_domain(
        MPI.COMM_SELF,
        GeometrySpec(
            "square", h=1 / 16, subdomain_size=1 / 4, structured=True, signorini=["bottom"]
        ),
    ).coarse
    assert isinstance(c.edge_dofs, Ragged) and isinstance(c.edge_coords, Ragged)
    fields = _pack(c)
    assert all(isinstance(v, (np.ndarray, int)) for v in fields.values())  # no per-edge objects
    back = _unpack(pickle.loads(pickle.dumps(fields)))
    for name in c.__dataclass_fields__:
        a, b = getattr(c, name), getattr(back, name)
        if isinstance(a, Ragged):
            assert _same(a.flat, b.flat) and _same(a.offsets, b.offsets), name
        elif isinstance(a, np.ndarray):
            assert _same(a, b), name
        else:
            assert a == b, name
    assert _same(back.edge_segments(), np.array([len(d) - 1 for d in c.edge_dofs]))
    # a CoarseStructure built from plain tuples stores Ragged rows
    plain = dict(vars(c), edge_dofs=tuple(c.edge_dofs), edge_coords=tuple(c.edge_coords))
    rebuilt = CoarseStructure(**plain)
    assert isinstance(rebuilt.edge_dofs, Ragged)
    assert _same(rebuilt.edge_dofs.flat, c.edge_dofs.flat) and _same(
        rebuilt.edge_coords.flat, c.edge_coords.flat
    )
