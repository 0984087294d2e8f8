"""Tests of particles.course.similarity."""
