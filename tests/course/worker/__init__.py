"""Tests of particles.course.worker."""
