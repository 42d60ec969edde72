# ruff: noqa: A005  # tests.io mirrors swarmtag.io; inside the tests package it shadows nothing
"""Tests of swarmtag.io: event-log schema, CSV and Parquet."""
