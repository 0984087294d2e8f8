"""Tests of particles.course.results."""
