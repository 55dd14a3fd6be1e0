"""Fixtures shared by the harness tests (their helpers live in fake_bench.py)."""

import pytest
from fake_bench import write_campaign


@pytest.fixture
def campaign_file(tmp_path):
    """``campaign_file(text, name="tiny.toml")``: the campaign ``text`` written into ``tmp_path`` and loaded."""
    return lambda text, name="tiny.toml": write_campaign(tmp_path, text, name)
