"""Every kind of bad input gets the exception of its status code, with a
message that names the array and the element; the server keeps serving
after each one. Bad arrays are refused before anything is sent; what only
the server can judge comes back as the server's error. What only one method
takes (the exponential map's centre and radius) is refused in that method's
test in test_client.py."""

from pathlib import Path

import numpy as np
import pytest

import geodex
from support import Server, random_points

MODEL = "torus"
ONE = np.array([[1.0, 0.0, 0.0]])


@pytest.fixture(scope="module")
def num_faces(client) -> int:
    return client.model(MODEL).num_faces


def good(num_faces: int) -> geodex.SurfacePoints:
    return random_points(num_faces, 40, 21)


def bad_pairs(num_faces: int):
    """(name, a, b, exception, words of the message): a and b of 40 pairs,
    the bad element at index 33."""

    def with_(points, faces=None, weights=None):
        f, w = points.faces.copy(), points.weights.copy()
        if faces is not None:
            f = faces(f)
        if weights is not None:
            w = weights(w)
        return (f, w)

    def at33(array, value):
        array[33] = value
        return array

    g = good(num_faces)
    return [
        ("negative face", with_(g, faces=lambda f: at33(f, -5)), g,
         geodex.InvalidArgument, "a.faces[33] is -5"),
        ("face past the model's count", g, with_(g, faces=lambda f: at33(f, num_faces)),
         geodex.OutOfRange, "b[33]"),
        ("NaN weight", g, with_(g, weights=lambda w: at33(w, [np.nan, 0.5, 0.5])),
         geodex.InvalidArgument, "b.weights[33]"),
        ("infinite weight", with_(g, weights=lambda w: at33(w, [np.inf, 0, 0])), g,
         geodex.InvalidArgument, "a.weights[33]"),
        ("weights not summing to 1", with_(g, weights=lambda w: at33(w, [0.5, 0.2, 0.2])), g,
         geodex.InvalidArgument, "a[33]"),
        ("negative weight", g, with_(g, weights=lambda w: at33(w, [1.5, -0.5, 0.0])),
         geodex.InvalidArgument, "b[33]"),
        ("weights of the wrong shape", (g.faces, g.weights[:, :2]), g,
         geodex.InvalidArgument, "a.weights has shape (40, 2), want (40, 3)"),
        ("a face id that is no whole number",
         with_(geodex.SurfacePoints(g.faces.astype(float), g.weights),
               faces=lambda f: at33(f, 2.5)), g,
         geodex.InvalidArgument, "a.faces[33] is 2.5"),
        ("pairs that do not pair up", g, (g.faces[:39], g.weights[:39]),
         geodex.InvalidArgument, "a has 40 points but b has 39"),
    ]


@pytest.mark.parametrize("batch_size", [1000, 16], ids=["one call", "streamed"])
def test_bad_pairs(server, client, num_faces, batch_size):
    with geodex.connect(server.address, batch_size=batch_size) as c:
        for name, a, b, error, words in bad_pairs(num_faces):
            with pytest.raises(error) as e:
                c.distance(MODEL, a, b)
            assert words in str(e.value), f"{name}: {e.value}"
            assert e.value.code_name in str(e.value)
            assert server.alive(), name
            g = good(num_faces)
            assert c.distance(MODEL, g, g).shape == (40,), f"not serving after {name}"


def test_unknown_models_and_versions(client, num_faces):
    g = good(num_faces)
    with pytest.raises(geodex.NotFound, match="nope"):
        client.distance("nope", g, g)
    with pytest.raises(geodex.NotFound):
        client.model("nope")
    with pytest.raises(geodex.NotFound):
        client.distance(MODEL, g, g, version=7)
    with pytest.raises(geodex.InvalidArgument, match="version"):
        client.distance(MODEL, g, g, version=-1)


def test_bad_options(client, num_faces):
    g = good(num_faces)
    with pytest.raises(geodex.InvalidArgument, match="tolerance"):
        client.distance(MODEL, g, g, tolerance=-0.1)
    with pytest.raises(geodex.InvalidArgument, match="refine_below must be finite"):
        client.distance(MODEL, g, g, refine_below=float("nan"))
    with pytest.raises(geodex.InvalidArgument, match="near_pairs"):
        client.distance(MODEL, g, g, near_pairs="fast")
    with pytest.raises(geodex.InvalidArgument, match="exact_corridor"):
        client.path(MODEL, g, g, exact_corridor=65)
    # Error bounds need a calibrated index; "cube" was built without.
    cube = random_points(client.model("cube").num_faces, 5, 22)
    with pytest.raises(geodex.FailedPrecondition):
        client.distance("cube", cube, cube, bounds=True)
    assert client.distance("cube", cube, cube).shape == (5,)


def test_bad_points_of_the_other_methods(client, num_faces):
    g = good(num_faces)
    past = (np.array([num_faces], np.int32), ONE)
    with pytest.raises(geodex.OutOfRange, match=r"targets\[0\]"):
        client.matrix(MODEL, g, past)
    with pytest.raises(geodex.OutOfRange, match=r"sources\[0\]"):
        client.field(MODEL, past)
    with pytest.raises(geodex.OutOfRange, match=r"b\[0\]"):
        client.path(MODEL, (g.faces[:1], g.weights[:1]), past)
    for radius, shown in [(-1.0, "-1"), (np.nan, "nan"), (np.inf, "inf")]:
        with pytest.raises(geodex.InvalidArgument, match=f"radius must be finite and > 0, got {shown}"):
            client.field(MODEL, g, radius=radius)
    with pytest.raises(geodex.OutOfRange, match=r"sources\[0\]"):
        client.field(MODEL, past, radius=1.0)
    with pytest.raises(geodex.InvalidArgument, match=r"xyz\[1\]"):
        client.locate(MODEL, [[0, 0, 0], [np.nan, 0, 0]])
    with pytest.raises(geodex.InvalidArgument, match=r"a\[1\] is \[1.0, 2.0, nan\]"):
        client.distance(MODEL, [[0, 0, 0], [1, 2, np.nan]], [[0, 0, 0], [0, 0, 1]], xyz=True)
    assert client.distance(MODEL, g, g).shape == (40,)


@pytest.fixture(scope="module")
def guarded(models_dir: Path, tmp_path_factory: pytest.TempPathFactory):
    """A second server on the same models, with a bearer token and a limit
    of 100 pairs per message."""
    tokens = tmp_path_factory.mktemp("tokens") / "tokens.txt"
    tokens.write_text("s3cret\n")
    s = Server(models_dir, tokens.parent / "server.log", "--token-file", str(tokens),
               "--max-pairs", "100")
    s.wait_serving(["torus"], token="s3cret")
    yield s
    s.stop()


def test_tokens_and_limits(guarded, num_faces):
    g = random_points(num_faces, 150, 23)
    with geodex.connect(guarded.address) as anonymous:
        with pytest.raises(geodex.Unauthenticated):
            anonymous.distance(MODEL, g, g)
    with geodex.connect(guarded.address, token="wrong") as wrong:
        with pytest.raises(geodex.Unauthenticated):
            wrong.models()
    with geodex.connect(guarded.address, token="s3cret", batch_size=1000) as c:
        with pytest.raises(geodex.ResourceExhausted, match="100"):
            c.distance(MODEL, g, g)  # one call of 150 pairs
    with geodex.connect(guarded.address, token="s3cret", batch_size=100) as c:
        assert c.distance(MODEL, g, g).shape == (150,)  # two batches of a stream
    assert guarded.alive()
