"""The LMS importers' own reading of our files: Moodle's through PHP's ``fgetcsv`` itself, Canvas's ported.

:func:`moodle_import` runs a tiny PHP script (Debian's ``php-cli``, installed by ``.ci/install-system-tools``)
that reads a file as Moodle's ``csv_import_reader`` and ``gradeimport_csv_load_data`` do. :func:`canvas_import`
is a port of Canvas's ``GradebookImporter`` header rules and student matching, run on a course whose users the
test gives.
"""

import csv
import json
import os
import re
import shutil
import subprocess
from dataclasses import dataclass, field

import pytest

# --- Moodle -------------------------------------------------------------------------------------------------
# moodle/moodle, lib/csvlib.class.php at commit cf29c007d2535bb90d623d0fad76ee8075ced722,
# csv_import_reader::load_csv_content (lines 92-188):
#   100  $content = core_text::trim_utf8_bom($content);
#   102  $content = preg_replace('!\r\n?!', "\n", $content);
#   104-109  $content = trim($content);  (no tab separator)
#   129  while ($fgetdata = fgetcsv($fp, 0, $csv_delimiter, $enclosure)) {   (PHP's default escape: "\\")
#   131-135  a line of one null cell (an empty line) is skipped
#   164-173  a row with another number of cells than the header: error 'csvweirdcolumns', nothing imported
#   179  $storedata = csv_export_writer::print_array($columns, ',', '"', true);   (fputcsv, stored again)
# csv_import_reader::next (lines 245-253):  if ($ser = fgetcsv($this->_fp)) { return $ser; }
# moodle/moodle, grade/import/csv/classes/load_data.php at commit 0289d8c7665458f8ffc47e34527598e15523f104:
#   prepare_import_grade_data: while ($line = $csvimport->next()) { if (count($line) <= 1) continue; ...
#       foreach ($line as $key => $value) { $value = clean_param($value, PARAM_RAW); $value = trim($value); ...
#   map_user_data_with_value, case 'useremail' (and 'username', 'useridnumber'):
#       // Skip invalid row with blank user field.
#       if (!empty($value)) { $this->studentid = $this->check_user_exists($value, $userfields[$mappingidentifier]); }
#   $this->studentid is set to null once, before the first line: a row whose identifier PHP calls empty keeps
#   the previous row's user (the first row: 'usermappingerrorusernotfound', the whole import aborted).
MOODLE_READER = r"""<?php
setlocale(LC_ALL, 'C.UTF-8');  // moodle_setlocale(): a UTF-8 locale
$content = file_get_contents($argv[1]);
$idcolumn = (int)$argv[2];
if (substr($content, 0, 3) === "\xEF\xBB\xBF") { $content = substr($content, 3); }
$content = preg_replace('!\r\n?!', "\n", $content);
$content = trim($content);
$fp = fopen('php://temp', 'w+b');
fwrite($fp, $content);
fseek($fp, 0);
$columns = array();
while ($fgetdata = fgetcsv($fp, 0, ',', '"')) {
    if (count($fgetdata) == 1) {
        if ($fgetdata[0] !== null) { $columns[] = $fgetdata; }
    } else {
        $columns[] = $fgetdata;
    }
}
$out = array('error' => null, 'header' => null, 'rows' => array(), 'users' => array());
if (!isset($columns[0])) { $out['error'] = 'csvemptyfile'; echo json_encode($out); exit(0); }
foreach ($columns as $rowdata) {
    if (count($rowdata) !== count($columns[0])) { $out['error'] = 'csvweirdcolumns'; echo json_encode($out); exit(0); }
}
$stored = fopen('php://temp', 'w+');
foreach ($columns as $row) { fputcsv($stored, $row, ',', '"'); }
fseek($stored, 0);
$out['header'] = array_map('trim', fgetcsv($stored));
$studentid = null;
while ($line = fgetcsv($stored)) {
    if (count($line) <= 1) { continue; }
    $line = array_map('trim', $line);
    if (!empty($line[$idcolumn])) { $studentid = $line[$idcolumn]; }
    if ($studentid === null) { $out['error'] = 'usermappingerrorusernotfound'; break; }
    $out['rows'][] = $line;
    $out['users'][] = $studentid;
}
echo json_encode($out);
"""


def php():
    """The ``php`` command, or skip the test (fail it in CI, where ``.ci/install-system-tools`` installs it)."""
    path = shutil.which("php")
    if path:
        return path
    message = "PHP's command line is not installed: run `sh .ci/install-system-tools` (make test does) or install php-cli"
    if os.environ.get("CI"):
        pytest.fail(message)
    pytest.skip(message)


def moodle_import(path, identifier=0, tmp=None):
    """Moodle's reading of a grade file: ``error``, ``header``, ``rows`` (trimmed cells) and ``users``.

    ``users[k]`` is the identifier whose user gets row ``k``'s grades: the row's own, or the previous row's
    when PHP calls the row's empty (see the Moodle lines above).
    """
    script = (tmp or path.parent) / "moodle_reader.php"
    script.write_text(MOODLE_READER)
    done = subprocess.run([php(), "-n", str(script), str(path), str(identifier)], capture_output=True, text=True,
                          timeout=60)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


# --- Canvas ---------------------------------------------------------------------------------------------------
# A port of instructure/canvas-lms, lib/gradebook_importer.rb at commit 00b222d77ee43d046e6aee0347c4ed5b27e1741f:
# csv_stream (CSV.foreach with converters [:nil, :decimal_comma_to_period], skip_lines /^[;, ]+$/, the column
# separator from identify_delimiter on the first 3 lines), check_for_non_student_row (the first row is the
# header; a row whose first cell includes "Points Possible" gives the points; a row whose cells all match
# /^\s*(Muted|Manual Posting.*)?\s*$/i is skipped), header? / row_has_student_headers? / update_column_count /
# last_student_info_column (Student, ID, then SIS Login ID, or SIS User ID and SIS Login ID [Integration ID]
# [Root Account]; the last student column must include "Section"), strip_non_assignment_columns (the
# NON_ASSIGNMENT_COLUMN_HEADERS joined as one regular expression), parse_assignments (Assignment.title_and_id,
# /\A(.*)\s\((\d+)\)\z/; by id, else by title, else a new assignment) and process_student (row[1].to_i among
# the course's users, else the SIS User ID, else the SIS Login ID pseudonym, else name == or sortable_name ==).
CANVAS_RESERVED = ["Current Score", "Current Points", "Current Grade", "Final Score", "Final Points",
                   "Final Grade", "Override Score", "Override Grade", "Override Status"]


@dataclass
class CanvasUser:
    """A user of the Canvas course: what Canvas's importer matches a row with."""

    id: int
    name: str
    sortable_name: str = ""
    sis_user_id: str = ""
    login_id: str = ""


@dataclass
class CanvasImport:
    """What Canvas's importer made of a file."""

    assignments: list
    points: dict
    rows: list = field(default_factory=list)  # (user or None, {assignment: grade}) per student row


def _decimal_comma_to_period(cell):
    if cell is None or not re.search(r"^-?[0-9.,]+%?$", cell, re.M):
        return cell
    parts = re.split(r"[,.]", cell)
    while parts and parts[-1] == "":  # Ruby's String#split drops trailing empty strings
        parts.pop()
    if not parts:
        return ""
    last = parts.pop()
    return last if not parts else "".join(parts) + "." + last


def _parse(text, sep):
    """Ruby's CSV, as strict as it is: an unclosed quote, a quote in an unquoted cell or text after a closing
    quote is a MalformedCSVError (the whole import fails); an empty unquoted cell is nil (None), ``""`` is ""."""
    rows, row, i, n = [], [], 0, len(text)
    stop = re.compile(rf"[{re.escape(sep)}\r\n]|$")
    while n:
        if i < n and text[i] == '"':
            j, parts = i + 1, []
            while True:
                k = text.find('"', j)
                assert k >= 0, f"MalformedCSVError: an unclosed quoted cell on row {len(rows) + 1}"
                parts.append(text[j:k])
                if text[k + 1:k + 2] != '"':
                    break
                parts.append('"')
                j = k + 2
            value, i = "".join(parts), k + 1
        else:
            end = stop.search(text, i).start()
            value, i = text[i:end] or None, end
            assert '"' not in (value or ""), f"MalformedCSVError: a quote in the unquoted cell {value!r}"
        row.append(value)
        if i >= n:
            rows.append(row)
            break
        if text[i] == sep:
            i += 1
            continue
        assert text[i] in "\r\n", f"MalformedCSVError: {text[i]!r} after a closing quote on row {len(rows) + 1}"
        i += 2 if text[i:i + 2] == "\r\n" else 1
        rows.append(row)
        row = []
        if i >= n:
            break
    return rows


def _separator(text):
    """identify_delimiter: ';' when it splits the first 3 lines into more (equal) fields than ','."""
    first = text.split("\n")[:3]
    counts = {}
    for sep in (";", ","):
        try:
            sizes = [len(next(csv.reader([line], delimiter=sep, strict=True), [])) for line in first]
        except csv.Error:
            sizes = [0, 1]
        counts[sep] = sizes[0] if len(set(sizes)) == 1 else 0
    return ";" if counts[";"] > counts[","] else ","


def canvas_import(text, users):
    """Canvas's importer on `text` (the CSV) for a course of `users` (:class:`CanvasUser`)."""
    sep = _separator(text)
    rows = [[_decimal_comma_to_period(c) for c in row] for row in _parse(text, sep)
            if not re.fullmatch(r"[;, ]+", sep.join(c or "" for c in row))]
    header, body = rows[0], rows[1:]
    assert len(header) > 3 and "Student" in header[0] and "ID" in header[1], "InvalidHeaderRow"
    columns = 3
    sis_user = sis_login = None
    if re.search(r"SIS\s+Login\s+ID", header[2] or ""):
        sis_login, columns = 2, 4
    elif re.search(r"SIS\s+User\s+ID", header[2] or "") and re.search(r"SIS\s+Login\s+ID", header[3] or ""):
        extra = 1 if re.search(r"Integration\s+ID", header[4] or "") else 0
        sis_user, sis_login, columns = 2, 3, columns + 2 + extra
        if re.search(r"Root\s+Account", header[4 + extra] or ""):
            columns += 1
    assert "Section" in (header[columns - 1] or ""), "InvalidHeaderRow: the last student column is not Section"
    reserved = re.compile("|".join(CANVAS_RESERVED))
    titles = [h for h in header[columns:] if not reserved.search(h or "")]
    assignments = {}
    for title in titles:
        named = re.fullmatch(r"(.*)\s\((\d+)\)", title, re.S)
        assignments[header.index(title)] = named.group(1) if named else title
    result = CanvasImport(list(assignments.values()), {})
    by_id = {u.id: u for u in users}
    for row in body:
        if row[0] is not None and "Points Possible" in row[0]:
            result.points = {t: row[i] for i, t in assignments.items()}
            continue
        if all(re.fullmatch(r"\s*(Muted|Manual Posting.*)?\s*", c, re.I | re.S) for c in row if c is not None):
            continue
        user = by_id.get(_to_i(row[1])) if (row[1] or "").strip() else None
        if user is None and sis_user is not None and (row[sis_user] or "").strip():
            user = next((u for u in users if u.sis_user_id and u.sis_user_id == row[sis_user]), None)
        if user is None and sis_login is not None and (row[sis_login] or "").strip():
            user = next((u for u in users if u.login_id and u.login_id == row[sis_login]), None)
        if user is None:
            user = next((u for u in users if row[0] in (u.name, u.sortable_name)), None)
        result.rows.append((user, {t: (row[i] or "").strip() for i, t in assignments.items()}))
    return result


def _to_i(text):
    """Ruby's String#to_i: leading white space, a sign and digits; 0 when there are none."""
    match = re.match(r"\s*([+-]?\d+)", text or "")
    return int(match.group(1)) if match else 0


# --- Feedback zips ---------------------------------------------------------------------------------------------
# instructure/canvas-lms, app/models/assignment.rb, Assignment#infer_comment_context_from_filename (as stored at
# the version whose generate_comments_from_files groups the files by user):
#     filename = File.basename(fullpath)
#     split_filename = filename.split('_')
#     user_id, attachment_id = split_filename.grep(/^\d+$/).take(2)
#     attachment_id = nil if split_filename.last =~ /^link/ || filename =~ /^\._/
#     ... ignored unless the attachment is one of that user's submission's attachments;
#     the comment's file is shown under attachment.display_name (the name of the submitted file).
def canvas_reupload(names):
    """(user id, attachment id) Canvas reads from each file name of a re-upload zip, None when it ignores it."""
    read = {}
    for fullpath in names:
        filename = fullpath.rsplit("/", 1)[-1]
        parts = filename.split("_")
        while parts and parts[-1] == "":  # Ruby's split drops trailing empty strings
            parts.pop()
        digits = [p for p in parts if re.fullmatch(r"\d+", p)][:2]
        user = digits[0] if digits else None
        attachment = digits[1] if len(digits) > 1 else None
        if (parts and re.match(r"link", parts[-1])) or filename.startswith("._"):
            attachment = None
        read[fullpath] = (user, attachment) if user and attachment else None
    return read


# moodle/moodle, mod/assign/feedback/file/importziplib.php at commit 0203d8f26027201de1d7d1ec8d8aa3cdcc4f5d5d,
# assignfeedback_file_zip_importer::is_valid_filename_for_import: directories and names starting with '.' or '~'
# are skipped; each path part is exploded on '_' (limit 5); a part of at least 4 pieces whose second is numeric and
# a participant, whose third and fourth name a plugin of the assignment (assignfeedback, file), gives the user and
# the file name (the rest of the path).
def moodle_feedback_import(names, participants, plugins=(("assignfeedback", "file"),)):
    """participant id -> [file name] Moodle imports from a feedback zip's names (`participants`: ids)."""
    found = {}
    for name in names:
        if name.endswith("/") or name.rsplit("/", 1)[-1].startswith((".", "~")):
            continue
        parts = name.split("/")
        while parts:
            info = parts.pop(0).split("_", 4)
            if len(info) < 4 or not re.fullmatch(r"\s*[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?\s*", info[1]):
                continue
            participant = int(float(info[1]))
            if participant not in participants or (info[2], info[3]) not in plugins:
                continue
            parts.insert(0, info[4] if len(info) > 4 else "")
            found.setdefault(participant, []).append("/".join(parts))
            break
    return found


# --- a graded folder ----------------------------------------------------------------------------------------


def graded_folder(out, records, options=None):
    """`out` as `particles grade --out` leaves it: its course record holding `records` as current results."""
    from particles.course.term.database import TermRecord

    term = TermRecord(out)
    run = term.start_run("particles grade (a test)", {})
    for record in records:
        term.save(run, record, options or {"public_only": False})
    term.finish_run(run)
    term.close()
    return out
