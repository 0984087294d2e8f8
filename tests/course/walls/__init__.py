"""Tests of particles.course.walls."""
