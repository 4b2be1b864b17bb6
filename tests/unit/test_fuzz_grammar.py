"""Fuzzing grammar (.aggl) and target (.aggt) files, both dialects: any text gives a grammar, or a
GrammarError that says file:line:column; never another exception.

Mutations start from the shipped grammar, the examples of docs/grammar.md and, when present, the
RoboComp AGM corpus in ../shared/corpus/aggl."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from grammar import GrammarError, parse_grammar, parse_target
from grammar.parser import default_grammar_path, load_grammar
from tests.support import REPO_ROOT
from tests.unit.fuzz_mutations import fuzz_settings, mutated_bytes, mutated_text, token_soup

CORPUS = REPO_ROOT.parent / "shared" / "corpus" / "aggl"
AGGL_WORDS = ("grammar", "types", "include", "rule", "target", "where", "precondition", "effect", "active",
              "passive", "dormant", "===", "=>", "->", "--", "{", "}", "(", ")", ":", "*", "not", "forall")


def _grammar_texts() -> list[str]:
    texts = [default_grammar_path().read_text(encoding="utf-8")]
    docs = (REPO_ROOT / "docs" / "grammar.md").read_text(encoding="utf-8")
    blocks = re.findall(r"```text\n(.*?)```", docs, re.S)[:2]
    texts += [re.sub(r"^include.*$", "", block, flags=re.M) for block in blocks]
    if CORPUS.is_dir():
        texts += [p.read_text(encoding="utf-8") for p in sorted(CORPUS.glob("*.aggl"))]
    return texts


GRAMMARS = _grammar_texts()
TARGETS = ["{\n\t200:omnirobot(1,1)\n\t60:room(1,1)\n\t200->60(in)\n}\nprecondition\n{\n}\n",
           'target { r:robot "a1":activity [state == "finished"] g:room r->g(in) } where a1.room != none\n']


def check_grammar_error(exc: GrammarError, file: str) -> None:
    assert exc.message.strip(), exc
    assert exc.file == file, f"the error names {exc.file!r}, not {file!r}: {exc}"
    assert exc.line >= 1 and exc.column >= 1, f"no position: {exc}"


def test_sources_parse() -> None:
    for text in GRAMMARS:
        parse_grammar(text, "source.aggl")
    for text in TARGETS:
        parse_target(text, "source.aggt")


@fuzz_settings(300)
@given(data=st.data())
def test_mutated_grammars_give_located_errors(data: st.DataObject) -> None:
    text = data.draw(mutated_text(data.draw(st.sampled_from(GRAMMARS), label="source")), label="text")
    try:
        parse_grammar(text, "fuzz.aggl")
    except GrammarError as exc:
        check_grammar_error(exc, "fuzz.aggl")


@fuzz_settings(100)
@given(text=st.one_of(st.text(max_size=200), token_soup(GRAMMARS[0], AGGL_WORDS), token_soup(GRAMMARS[-1], AGGL_WORDS)))
def test_random_text_grammars_give_located_errors(text: str) -> None:
    try:
        parse_grammar(text, "random.aggl")
    except GrammarError as exc:
        check_grammar_error(exc, "random.aggl")


@fuzz_settings(150)
@given(data=st.data())
def test_mutated_targets_give_located_errors(data: st.DataObject) -> None:
    source = data.draw(st.sampled_from(TARGETS), label="source")
    text = data.draw(st.one_of(mutated_text(source), token_soup(source, AGGL_WORDS)), label="text")
    try:
        parse_target(text, "fuzz.aggt")
    except GrammarError as exc:
        check_grammar_error(exc, "fuzz.aggt")


@pytest.fixture(scope="module")
def workdir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("fuzz_grammar")


@fuzz_settings(40)
@given(content=mutated_bytes(GRAMMARS[0]))
def test_grammar_files_with_stray_bytes_give_located_errors(workdir: Path, content: bytes) -> None:
    path = workdir / "bytes.aggl"
    path.write_bytes(content)
    try:
        load_grammar(path)
    except GrammarError as exc:
        check_grammar_error(exc, str(path))
