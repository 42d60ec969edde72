import stat

import pytest

from swarmtag.console.auth import RateLimiter, load_or_create_token, token_matches
from swarmtag.errors import ConfigError


def test_token_file_is_created_private_and_reused(tmp_path):
    path = tmp_path / "token"
    token = load_or_create_token(path)
    assert len(token) >= 32
    assert stat.S_IMODE(path.stat().st_mode) == 0o600
    assert load_or_create_token(path) == token
    assert load_or_create_token(tmp_path / "other") != token


def test_a_readable_token_file_is_made_private(tmp_path):
    path = tmp_path / "token"
    token = load_or_create_token(path)
    path.chmod(0o644)
    assert load_or_create_token(path) == token
    assert stat.S_IMODE(path.stat().st_mode) == 0o600


def test_a_file_that_holds_something_else_is_refused(tmp_path):
    path = tmp_path / "notes.txt"
    path.write_text("my shopping list\n")
    with pytest.raises(ConfigError, match="not a console token"):
        load_or_create_token(path)
    assert path.read_text() == "my shopping list\n"


def test_token_file_in_a_missing_folder_is_one_clear_error(tmp_path):
    with pytest.raises(ConfigError, match="cannot write it"):
        load_or_create_token(tmp_path / "missing" / "token")


def test_token_matches():
    assert token_matches("a" * 40, "a" * 40)
    assert not token_matches("a" * 39, "a" * 40)
    assert not token_matches(None, "a" * 40)


def test_rate_limiter_refills():
    limiter = RateLimiter(per_second=2.0, burst=3)
    assert [limiter.allow("x", now=0.0) for _ in range(4)] == [True, True, True, False]
    assert limiter.allow("x", now=0.5)
    assert not limiter.allow("x", now=0.5)
    assert limiter.allow("y", now=0.5)
