r"""How Canvas's and Moodle's gradebook importers read a file: what the LMS files are written for.

The grade files of :mod:`particles.course.results.lms` are read by code we do not run: Canvas's
``GradebookImporter`` (Ruby's CSV with Canvas's converters, then its student matching) and Moodle's
``csv_import_reader`` and ``gradeimport_csv_load_data`` (PHP's ``fgetcsv``, then its user look-up). This module
holds what they do that changes a cell or a match, so that the writer can write for them and say, for each
roster student, whether the grade will reach them:

* :func:`canvas_read`: Canvas rewrites every cell that looks like a number with a decimal comma;
* :func:`canvas_match`: which column Canvas will find a student by (``ID``, ``SIS User ID``, ``SIS Login ID``,
  or the name, exactly), or none (:func:`canvas_unmatched` says why);
* :func:`moodle_cell`: a cell as PHP's ``fgetcsv``, whose escape character is the backslash, reads it back;
* :func:`moodle_empty` and :func:`moodle_left_out`: an identifier Moodle skips (PHP's ``empty()``), whose row's
  grades would go to the previous row's user.

The tests run the files written through the importers' own reading (PHP's ``fgetcsv`` itself, and a port of
Canvas's header and matching rules): ``tests/course/results/test_importers.py``.

References
----------
Canvas: ``lib/gradebook_importer.rb`` (https://github.com/instructure/canvas-lms). Moodle:
``lib/csvlib.class.php`` and ``grade/import/csv/classes/load_data.php`` (https://github.com/moodle/moodle).
"""

import re

__all__ = ["FORMULA_STARTS", "canvas_read", "canvas_match", "canvas_unmatched", "moodle_empty", "moodle_cell",
           "moodle_left_out"]

FORMULA_STARTS = ("=", "+", "-", "@", "\t", "\r")
"""The first characters a spreadsheet reads as a formula: such a text cell is written with a leading ``'``."""

_CANVAS_NUMBER = re.compile(r"^-?[0-9.,]+%?$", re.M)  # Ruby's ^ and $ are line anchors
_PHP_TRIM = " \t\n\r\0\x0b"  # what PHP's trim() removes
_MOODLE_QUOTED = (",", '"', "\\", "\n", "\r", "\t", " ")  # what PHP's fputcsv quotes a cell for


def canvas_read(cell):
    """A cell as Canvas's importer reads it: its ``decimal_comma_to_period`` converter applied.

    Canvas parses the file with converters that rewrite every cell that looks like a number (digits, ``.`` and
    ``,``, an optional ``-`` and ``%``): the last ``.`` or ``,`` becomes the decimal point, the others are
    dropped (``1,234`` reads ``1.234``, ``1.234,5`` reads ``1234.5``). Ruby's ``split`` drops trailing empty
    parts (``12,`` reads ``12``).

    Examples
    --------
    >>> canvas_read("1,234"), canvas_read("2.5"), canvas_read("S-001"), canvas_read("1.234,5")
    ('1.234', '2.5', 'S-001', '1234.5')
    """
    cell = str(cell)
    if not _CANVAS_NUMBER.search(cell):
        return cell
    parts = re.split(r"[,.]", cell)
    while parts and parts[-1] == "":
        parts.pop()
    if not parts:
        return ""
    last = parts.pop()
    return last if not parts else "".join(parts) + "." + last


def canvas_match(student, written):
    """How Canvas's importer will find a roster student in the Canvas file: the column it matches, or "".

    Canvas tries the ``ID`` column (a number), then ``SIS User ID``, then ``SIS Login ID`` (each as
    :func:`canvas_read` reads it), then the ``Student`` column against each user's name and sortable name,
    exactly.

    Parameters
    ----------
    student : RosterStudent
        Its ``canvas_id``, ``sis_user_id``, ``sis_login_id`` and ``name``.
    written : str
        The ``Student`` cell as the file holds it (the name with a leading ``'`` when it starts like a formula).

    Returns
    -------
    str
        ``"ID"``, ``"SIS User ID"``, ``"SIS Login ID"``, ``"name"`` (only by the roster's ``name``, when the file
        holds it as Canvas shows it), or ``""``: Canvas cannot match the row and asks for it by hand on upload.
    """
    if student.canvas_id.strip():
        return "ID"
    for column, value in (("SIS User ID", student.sis_user_id), ("SIS Login ID", student.sis_login_id)):
        if value.strip() and canvas_read(value) == value:
            return column
    if student.name and written == student.name and canvas_read(written) == written:
        return "name"
    return ""


def canvas_unmatched(student, written):
    """Why Canvas cannot match a roster student (:func:`canvas_match` gave ""), in one sentence."""
    given = [f"{label} {value!r}" for label, value in (("SIS User ID", student.sis_user_id),
                                                       ("SIS Login ID", student.sis_login_id)) if value.strip()]
    parts = [f"Canvas reads its {' and '.join(given)} as a number" if given else
             "it has no Canvas ID, SIS User ID or SIS Login ID"]
    if not student.name:
        parts.append("the roster gives no name")
    elif written != student.name:
        parts.append(f"its name is written {written!r} (a leading ' so that spreadsheets do not run it), which "
                     "is not the name Canvas knows")
    else:
        parts.append(f"Canvas reads its name {student.name!r} as the number {canvas_read(student.name)!r}")
    return "; ".join(parts)


def moodle_empty(value):
    """Whether Moodle's importer skips the user look-up for `value`: PHP's ``empty()`` after ``trim()``.

    PHP calls the strings ``""`` and ``"0"`` empty; Moodle trims every cell (spaces, tabs, line breaks, NUL,
    vertical tab) first, so ``" 0 "`` is empty too, and ``"00"`` or ``"0.0"`` are not.

    Examples
    --------
    >>> [moodle_empty(v) for v in ("", "0", " 0\\t", "00", "0.0", "a")]
    [True, True, True, False, False, False]
    """
    return str(value).strip(_PHP_TRIM) in ("", "0")


def moodle_cell(text):
    r"""A cell written for PHP's ``fgetcsv`` (comma, ``"`` to quote, ``\`` to escape), as Moodle reads it.

    A cell holding a comma, quote, backslash, white space or line break is quoted; inside, a ``"`` is doubled
    unless a backslash escapes it (PHP keeps both characters of an escape, so ``\"`` reads ``\"``); a cell whose
    last backslash would escape the closing quote gets a space after it, which Moodle trims from every cell. This
    is the format of PHP's own ``fputcsv``, which Moodle uses again to store the file between its preview and its
    import, so the cell survives both readings.

    Examples
    --------
    >>> print(moodle_cell('Gus\\", jr'), moodle_cell("Lee"), moodle_cell('say "hi" now'), moodle_cell("C:\\"))
    "Gus\", jr" Lee "say ""hi"" now" "C:\ "
    """
    text = str(text)
    if not any(c in text for c in _MOODLE_QUOTED):
        return text
    out, escaped = ['"'], False
    for c in text:
        if escaped:
            escaped = False
        elif c == "\\":
            escaped = True
        elif c == '"':
            out.append('"')
        out.append(c)
    return "".join(out) + (' "' if escaped else '"')


def moodle_left_out(student, identifier):
    """Why a roster student cannot be a row of the Moodle file with `identifier` ("" when it can): "has no email"...

    Parameters
    ----------
    student : RosterStudent
    identifier : {"email", "username", "idnumber"}
    """
    value = getattr(student, identifier)
    if not value.strip(_PHP_TRIM):
        return f"has no {identifier}"
    if moodle_empty(value):
        return (f"has {identifier} {value!r}, which Moodle's importer (PHP's empty()) "
                "reads as no identifier: the row's grades would go to the previous row's user")
    if "\n" in value or "\r" in value:
        return f"has a line break in its {identifier}, which matches no Moodle user"
    return ""
