"""A user's mistake ends a benchmark script with one line, not a traceback; a bug still raises."""

import pytest

from afford.errors import UserError, exit_on_user_error


def test_a_user_error_ends_a_script_with_one_line_and_status_2(capsys):
    def main():
        raise UserError("nope: not a dataset")

    with pytest.raises(SystemExit) as ended:
        exit_on_user_error(main)
    assert ended.value.code == 2
    assert capsys.readouterr().err == "error: nope: not a dataset\n"


def test_any_other_exception_goes_through_as_the_bug_it_is():
    def main():
        raise KeyError("a bug")

    with pytest.raises(KeyError):
        exit_on_user_error(main)
