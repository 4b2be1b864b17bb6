"""dsr.attr_values: an attribute value narrowed to what its reader expects, failing as float()/list() did."""

import pytest

from dsr.attr_values import as_float, as_floats, as_strs


def test_as_float_takes_numbers_and_numeric_strings() -> None:
    assert as_float(2) == 2.0
    assert as_float(True) == 1.0          # bool is an int, as for float()
    assert as_float("1.5") == 1.5


@pytest.mark.parametrize("value", [[1.0], None, {"x": 1}])
def test_as_float_refuses_other_kinds_with_type_error(value: object) -> None:
    with pytest.raises(TypeError, match="expected a number"):
        as_float(value)


def test_as_float_refuses_a_word_with_value_error() -> None:
    with pytest.raises(ValueError):
        as_float("kitchen")


def test_as_floats_and_as_strs_take_lists_only() -> None:
    assert as_floats([1, 2.5]) == [1.0, 2.5]
    assert as_floats([]) == []
    assert as_strs(["a", 3]) == ["a", "3"]
    with pytest.raises(TypeError, match="list of numbers"):
        as_floats(3.0)
    with pytest.raises(TypeError, match="expected a list"):
        as_strs("ab")     # a string is not taken for its characters
