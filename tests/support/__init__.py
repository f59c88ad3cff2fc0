"""Helpers the tests share (fakes, reference implementations, protocol clients); not tests."""
