"""Tests of hybridtable.studies."""
