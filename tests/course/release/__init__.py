"""Tests of particles.course.release."""
