"""Tests of swarmtag.analysis: KPIs, bootstrap statistics, comparisons, curves."""
