"""Loading parameters costs the same per key however many there are (core/params.py): setting a
key never scans the sources of every other parameter, so a 150k-key file loads in seconds
(bench/param_load_bench.py times it). Counted here, not timed: how many recorded sources a load
walks through, which grew with the square of the keys."""

from __future__ import annotations

from twil_control.core.params import ParamServer


class CountingDict(dict):
    """A dict that counts the keys iterated over (the scans a set would make)."""

    walked = 0

    def __iter__(self):
        for key in super().__iter__():
            CountingDict.walked += 1
            yield key


def _yaml(tmp_path, n: int):
    path = tmp_path / f"params_{n}.yaml"
    path.write_text(
        "".join((f"ns{i // 100}:\n" if i % 100 == 0 else "") + f"  key_{i}: {i}.5\n" for i in range(n))
    )
    return path


def test_loading_a_file_walks_no_other_parameters_sources(tmp_path):
    for n in (1000, 4000):
        server = ParamServer()
        server._sources = CountingDict()
        CountingDict.walked = 0
        server.load_file(_yaml(tmp_path, n), "/robot")
        assert len(server.names()) == n
        assert CountingDict.walked == 0, f"{n} keys walked {CountingDict.walked} sources"
    # key i is on line i + i // 100 + 2 (one namespace line per 100 keys)
    assert server.source_of("/robot/ns39/key_3999").endswith("params_4000.yaml:4040")


def test_setting_params_one_by_one_walks_no_other_parameters_sources():
    server = ParamServer()
    server._sources = CountingDict()
    CountingDict.walked = 0
    for i in range(5000):
        server.set(f"/g{i // 100}/p{i}", float(i), source=f"big.launch:{i + 2}")
    assert CountingDict.walked == 0
    assert server.get("/g49/p4999") == 4999.0 and server.source_of("/g49/p4999") == "big.launch:5001"


def test_a_namespace_replaced_by_a_value_still_forgets_its_sources():
    server = ParamServer()
    server.load_data({"a": {"b": 1, "c": {"d": 2}}}, "/", file="one.yaml", lines={("a", "b"): 2})
    server.set("/a", 5, source="two.yaml:1")
    assert server.get("/a") == 5 and server.source_of("/a") == "two.yaml:1"
    assert server.source_of("/a/b") is None and server.files_under("/a") == ["two.yaml"]
