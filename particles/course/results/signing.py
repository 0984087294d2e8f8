"""Signed records: how the driver knows that a pytest session's results are the session's own.

The driver makes a new random key per session and hands it over through an
inherited pipe (:data:`TOKEN_FD`); the session signs its records file with it
(:func:`sign_records`) and the driver reads it back only with a valid
signature (:func:`read_records`). A worker never sees the key.
"""

import hashlib
import hmac
import json
from pathlib import Path

__all__ = ["TOKEN_FD", "sign_records", "read_records"]

TOKEN_FD = "PARTICLES_GRADING_TOKEN_FD"
"""Environment variable of a pytest session naming an inherited pipe that holds its signing key.

:func:`grade_batch` makes a new random key per session, writes it into a
pipe, closes its end and starts pytest with the other end inherited; the
plugin reads the key at start-up, before any worker exists, closes the pipe
and signs its records with it (:func:`sign_records`). The key lives only in
the memory of the driver and of the session: the variable holds a file
descriptor number, and workers get a clean environment and no inherited
descriptors (:class:`particles.course.worker.process.Worker`)."""


def sign_records(body, token):
    """The signature of a records file's `body` (str): hex HMAC-SHA256 under the session's key `token` (bytes)."""
    return hmac.new(token, body.encode("utf-8"), hashlib.sha256).hexdigest()


def read_records(path, token):
    """The submissions of a signed records file (id -> record), or None when it is missing, unsigned or altered.

    Parameters
    ----------
    path : path
        The file the pytest session wrote (``--grading-results``).
    token : bytes
        The session's key (see :data:`TOKEN_FD`).
    """
    try:
        signed = json.loads(Path(path).read_text())
        body, signature = signed["body"], signed["signature"]
        if not (isinstance(body, str) and isinstance(signature, str)
                and hmac.compare_digest(sign_records(body, token), signature)):
            return None
        return {str(s["id"]): s for s in json.loads(body)["submissions"]}
    except (OSError, UnicodeDecodeError, ValueError, KeyError, TypeError):
        return None
