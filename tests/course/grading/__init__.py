"""Tests of particles.course.grading."""
