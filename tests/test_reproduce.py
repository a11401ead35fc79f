from jaxrod.reproduce import compare_printed


def test_compare_printed():
    assert compare_printed(2.8931, "2.893") == "round"
    assert compare_printed(3.22667, "3.226") == "trunc"
    assert compare_printed(3.22667, "3.227") == "round"
    assert compare_printed(3.3, "3.226") == "MISMATCH"
    assert compare_printed(96.0, "96.00") == "round"
