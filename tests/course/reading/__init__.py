"""Tests of particles.course.reading."""
