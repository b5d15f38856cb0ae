"""Reading pipeline YAML with the place of every key, and applying ``--set`` overrides.

:func:`read_yaml` parses a document into plain dicts and lists whose
mappings (:class:`YAMLMapping`) remember ``file:line`` of each key, so that
:mod:`hht3d.pipeline.validation` can say where a problem is; :func:`at` gives
that place.  :func:`apply_overrides` applies the CLI's ``--set KEY.PATH=VALUE``
to a read document, recording ``--set ...`` as the place of what it sets.
Nothing here knows what a pipeline contains.
"""

from __future__ import annotations

import re
from collections.abc import Collection, Iterable
from typing import Any

import yaml

from ..errors import MAX_SHOWN, PipelineError, did_you_mean, one_line, shown

__all__ = [
    "YAMLMapping",
    "MAX_YAML_VALUES",
    "read_yaml",
    "at",
    "known_keys",
    "as_mapping",
    "apply_overrides",
    "add_implicit_load",
]


# -- YAML with line numbers ------------------------------------------------------------------------
class YAMLMapping(dict):
    """A YAML mapping that remembers where it and each of its keys came from (``file:line``)."""

    def __init__(self, where: str):
        super().__init__()
        self.where = where
        self.key_where: dict = {}

    def at(self, key: Any) -> str:
        return self.key_where.get(key, self.where)


#: Most values a pipeline may expand to through YAML aliases (``&a`` ... ``*a``); real pipelines
#: have a few hundred, an alias bomb billions.
MAX_YAML_VALUES = 100_000

#: YAML 1.2 floats (``1e9``, ``1e-8``), which YAML 1.1 and so PyYAML read as text.
_FLOAT = re.compile(r"^[-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?$|^[-+]?\.(inf|Inf|INF)$|^\.(nan|NaN|NAN)$")


class _YAMLSyntaxError(PipelineError):
    """Text that is not YAML (``--set`` then takes it as a plain string)."""


def _expanded_size(node: Any, sizes: dict, source: str) -> int:
    """How many values ``node`` stands for once every alias is expanded (memoised by node)."""
    key = id(node)
    if key in sizes:
        if sizes[key] is None:
            raise PipelineError(
                f"{source}:{node.start_mark.line + 1}: an alias refers to its own anchor; "
                "a pipeline cannot be recursive"
            )
        return sizes[key]
    sizes[key] = None
    children = (
        node.value
        if isinstance(node, yaml.SequenceNode)
        else [n for pair in node.value for n in pair]
        if isinstance(node, yaml.MappingNode)
        else []
    )
    sizes[key] = 1 + sum(_expanded_size(child, sizes, source) for child in children)
    if sizes[key] > MAX_YAML_VALUES:
        raise PipelineError(
            f"{source}:{node.start_mark.line + 1}: this YAML expands to more than "
            f"{MAX_YAML_VALUES} values through aliases (&anchor, *alias); write the pipeline "
            "out without them"
        )
    return sizes[key]


def read_yaml(text: str, source: str) -> Any:
    """Parse YAML, keeping ``source:line`` of every mapping key; duplicate keys are errors.

    Floats are read as YAML 1.2 does (``1e-8`` is a number, not text).
    A document of more than :data:`MAX_YAML_VALUES` values is refused as
    soon as the parser reaches that many, and one that aliases expand past
    that many before anything is built from it.  A one-line ``text`` (a
    ``--set`` value) is located by ``source`` alone.

    Raises
    ------
    PipelineError
        ``"source:LINE:COLUMN: YAML syntax error: ..."``, an alias bomb, or
        nesting too deep.
    """

    def place(node: Any) -> str:
        return f"{source}:{node.start_mark.line + 1}" if "\n" in text.strip() else source

    class Loader(yaml.SafeLoader):
        nodes = 0

        def compose_node(self, parent: Any, index: Any) -> Any:
            self.nodes += 1
            if self.nodes > MAX_YAML_VALUES:
                raise PipelineError(
                    f"{source}:{self.peek_event().start_mark.line + 1}: the YAML holds more than "
                    f"{MAX_YAML_VALUES} values; list input files with a folder or a glob, and "
                    "outputs with path placeholders"
                )
            return super().compose_node(parent, index)

        def get_single_node(self) -> Any:
            node = super().get_single_node()
            if node is not None:
                _expanded_size(node, {}, source)
            return node

    def mapping(loader: Any, node: Any) -> Any:
        loader.flatten_mapping(node)
        result = YAMLMapping(place(node))
        for key_node, value_node in node.value:
            key = loader.construct_object(key_node, deep=True)
            at = place(key_node)
            if not isinstance(key, (str, int, float, bool)) or key is None:
                raise PipelineError(f"{at}: a mapping key must be a plain name, got {shown(key)}")
            if key in result:
                raise PipelineError(f"{at}: duplicate key {shown(key)} (first at {result.at(key)})")
            result[key] = loader.construct_object(value_node, deep=True)
            result.key_where[key] = at
        return result

    Loader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, mapping)
    Loader.add_implicit_resolver("tag:yaml.org,2002:float", _FLOAT, list("-+0123456789."))
    try:
        return yaml.load(text, Loader=Loader)  # a SafeLoader subclass
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        reason = ": ".join(filter(None, [exc.context, exc.problem]))
        raise _YAMLSyntaxError(
            f"{source}:{mark.line + 1}:{mark.column + 1}: YAML syntax error: {one_line(reason)}"
        ) from None
    except yaml.YAMLError as exc:
        raise _YAMLSyntaxError(f"{source}: YAML syntax error: {one_line(exc)}") from None
    except RecursionError:
        raise PipelineError(f"{source}: the YAML is nested too deeply") from None


# -- --set overrides ---------------------------------------------------------------------------------
def apply_overrides(document: Any, overrides: Iterable[str]) -> None:
    """Apply ``key.path=value`` overrides in place (values parsed as YAML).

    A path component names a mapping key, a list index, or the ``id`` (or
    ``op``) of a step in ``steps``: ``steps.hht.params.max_imfs=4``,
    ``inputs=[a.ply, b.ply]``, ``outputs.folder=out/run1``.

    Parameters
    ----------
    document : dict
        The pipeline document, as read from YAML; changed in place.
    overrides : iterable of str
        ``KEY.PATH=VALUE`` texts, applied in order.

    Examples
    --------
    >>> from hht3d.pipeline import apply_overrides
    >>> document = {"steps": [{"id": "hht", "op": "hht", "params": {"max_imfs": 6}}], "outputs": {}}
    >>> apply_overrides(document, ["steps.hht.params.max_imfs=2", "outputs.folder=out/run1"])
    >>> document["steps"][0]["params"], document["outputs"]
    ({'max_imfs': 2}, {'folder': 'out/run1'})
    """
    for text in overrides:
        where = f"--set {one_line(text, MAX_SHOWN)}"
        path, sep, raw = text.partition("=")
        keys = path.strip().split(".")
        if not sep or not all(keys):
            raise PipelineError(f"{where}: expected KEY.PATH=VALUE, e.g. steps.hht.params.max_imfs=4")
        try:
            value = read_yaml(raw, where) if raw.strip() else ""
        except _YAMLSyntaxError:
            value = raw
        node = document
        for depth, key in enumerate(keys[:-1]):
            node = _child(node, key, ".".join(keys[: depth + 1]), where)
        _assign(node, keys[-1], value, where)


def _child(node: Any, key: str, dotted: str, where: str) -> Any:
    if isinstance(node, list):
        return node[_index(node, key, dotted, where)]
    if not isinstance(node, dict):
        raise PipelineError(f"{where}: {dotted.rpartition('.')[0] or 'the document'} is not a mapping")
    if key not in node or node[key] is None:
        _assign(node, key, YAMLMapping(where), where)
    return node[key]


def _index(items: list, key: str, dotted: str, where: str) -> int:
    if key.isdigit() and int(key) < len(items):
        return int(key)
    names = [item.get("id", item.get("op")) if isinstance(item, dict) else None for item in items]
    if key not in names:
        raise PipelineError(
            f"{where}: {dotted} matches no list item (give an index < {len(items)} or a "
            f"step id){did_you_mean(key, [n for n in names if isinstance(n, str)])}"
        )
    return names.index(key)


def _assign(node: Any, key: str, value: Any, where: str) -> None:
    if isinstance(node, list):
        node[_index(node, key, key, where)] = value
    elif isinstance(node, dict):
        node[key] = value
        if isinstance(node, YAMLMapping):
            node.key_where[key] = where
    else:
        raise PipelineError(f"{where}: cannot set {shown(key)} inside a {type(node).__name__}")


def at(mapping: Any, key: Any = None) -> str:
    """Where ``mapping`` (or its ``key``) came from: ``file:line``, or ``--set`` for values an override made."""
    if isinstance(mapping, YAMLMapping):
        return mapping.at(key) if key is not None else mapping.where
    return "--set"


def known_keys(mapping: Any, known: Collection[str], what: str) -> None:
    """Refuse a key of ``mapping`` not among ``known`` (``what`` names the mapping), with a "did you mean"."""
    for key in mapping:
        if key not in known:
            raise PipelineError(f"{at(mapping, key)}: unknown key {shown(key)} in {what}{did_you_mean(key, known)}")


def as_mapping(value: Any, where: str, what: str) -> dict:
    """``value`` if it is a mapping, else an error naming ``where`` and ``what``."""
    if not isinstance(value, dict):
        raise PipelineError(f"{where}: {what} must be a mapping (key: value lines), got {shown(value)}")
    return value


def add_implicit_load(document: Any) -> None:
    """Steps without a ``load`` start with ``{id: load, op: load}`` (which ``--set`` can then reach)."""
    steps = document.get("steps")
    if isinstance(steps, list) and not any(isinstance(e, dict) and e.get("op") == "load" for e in steps):
        implicit = YAMLMapping(at(document, "steps"))
        implicit.update(id="load", op="load")
        steps.insert(0, implicit)
