import numpy as np

from fivid.report.html import _cell


def test_cells_show_not_computed_values_as_a_dash():
    assert _cell(float("nan")) == "<td>—</td>"
    assert _cell(np.float64("nan")) == "<td>—</td>"
    assert _cell(None) == "<td>—</td>"
    assert _cell(2.30912) == '<td class="num">2.309</td>'
    assert _cell(True) == '<td class="pass">pass</td>'
