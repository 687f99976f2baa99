"""The shared CSV reader of published and measured tables (soilcal.config.load.read_table):
a row with another number of fields than the header is refused by its line instead of
shifting the columns."""

from __future__ import annotations

import math

import pytest

from soilcal.config.load import read_table
from soilcal.errors import InputError


def _refused(tmp_path, text: str) -> InputError:
    p = tmp_path / "t.csv"
    p.write_text(text)
    with pytest.raises(InputError) as e:
        read_table(p)
    assert e.value.path == str(p)
    return e.value


def test_decimal_comma_in_every_row_is_refused_not_shifted(tmp_path):
    # header: 3 fields; each row's unquoted decimal comma makes 4 (pandas alone would take
    # the first column as the index and move every value one column to the left)
    e = _refused(tmp_path, "plate,draft_N,depth_mm\n1,155,4,30\n2,160,2,30\n")
    assert (e.field, e.expected, e.got) == ("line 2", "3 fields, as many as the header", "4 fields")


def test_one_row_with_a_field_too_few_or_too_many(tmp_path):
    e = _refused(tmp_path, "a,b,c\n1,2,3\n4,5\n7,8,9\n")
    assert (e.field, e.got) == ("line 3", "2 fields")
    e = _refused(tmp_path, "a,b,c\n1,2,3\n4,5,6\n7,8,9,10\n")
    assert (e.field, e.got) == ("line 4", "4 fields")


def test_line_counts_blank_lines_and_quoted_line_breaks(tmp_path):
    # the record "x<newline>y",2,3 spans lines 2-3; the blank line 4 is skipped; line 5 is short
    e = _refused(tmp_path, 'a,b,c\n"x\ny",2,3\n\n4,5\n')
    assert e.field == "line 5"


def test_trailing_empty_spreadsheet_rows_are_not_rows_of_the_table(tmp_path):
    p = tmp_path / "t.csv"
    p.write_text("a,b,c\n1,2,3\n4,5,6\n,,\n,\n\n,,\n")
    df = read_table(p)
    assert list(df.columns) == ["a", "b", "c"] and df.to_numpy().tolist() == [[1, 2, 3], [4, 5, 6]]


def test_an_empty_row_between_data_rows_stays_a_row_of_empty_cells(tmp_path):
    p = tmp_path / "t.csv"
    p.write_text("a,b,c\n1,2,3\n,,\n4,5,6\n,,\n")
    df = read_table(p)
    assert len(df) == 3 and all(math.isnan(x) for x in df.iloc[1].to_numpy())
    assert df.iloc[2].tolist() == [4, 5, 6]


def test_quoted_commas_and_crlf_are_fields_not_separators(tmp_path):
    p = tmp_path / "t.csv"
    p.write_text('a,b\r\n"1,5",x\r\n')
    df = read_table(p)
    assert df.to_dict("records") == [{"a": "1,5", "b": "x"}]


def test_header_cells_are_stripped(tmp_path):
    p = tmp_path / "t.csv"
    p.write_text("plate , draft_N \n1,155.4\n")
    df = read_table(p)
    assert list(df.columns) == ["plate", "draft_N"]
    assert df["draft_N"].tolist() == [155.4]


def test_column_named_twice_is_named_not_renamed(tmp_path):
    # columns 2 and 4 are both draft_N (the second with a trailing space); pandas alone
    # would call the second "draft_N.1", a column the user never wrote
    e = _refused(tmp_path, "plate,draft_N,depth_mm,draft_N \n1,155.4,30,160.2\n")
    assert (e.field, e.expected, e.got) == ("column draft_N", "a column named once in the header",
                                            "columns 2 and 4")


def test_semicolon_separated_export_is_refused(tmp_path):
    e = _refused(tmp_path, "plate;draft_N;depth_mm\n1;155,4;30\n2;160,2;30\n")
    assert e.field == "<file>"
    assert "t.csv: <file>: expected a comma-separated table with decimal points" in str(e)
    assert "separated by ';'" in str(e)


@pytest.mark.parametrize("before", ['""\n', '""\n""\n', ' \n""\r\n', '"\n"\n'])
def test_empty_lines_before_the_header_are_skipped_whatever_their_quotes(tmp_path, before):
    # a line of one empty quoted cell is no header: pandas alone would take it for one
    # (a table of one unnamed column, or a field-count error two lines on)
    p = tmp_path / "t.csv"
    p.write_text(before + "a,b,c\n1,2,3\n4,5,6\n", newline="")
    df = read_table(p)
    assert list(df.columns) == ["a", "b", "c"]
    assert df.to_numpy().tolist() == [[1, 2, 3], [4, 5, 6]]


def test_a_row_too_long_after_skipped_lines_is_named_by_its_line(tmp_path):
    e = _refused(tmp_path, '""\n\na,b,c\n1,2,3\n4,5,6,7\n')
    assert (e.field, e.got) == ("line 5", "4 fields")
