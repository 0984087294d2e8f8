"""Whose fault is a failure: the function a test judges, or a helper of it that fails its own tests.

A downstream function fails when a function it calls is wrong (``measured_order`` when ``midpoint_step``
evaluates f at the wrong time, ``provot_project`` when ``provot_pass`` loses corrections). The tests of
the downstream function see only its wrong result; the fix is in the helper. Two pieces say so:

* :func:`helpers` reads the submission's syntax trees (nothing is run) for the functions of the notebook
  that a function uses, directly or through other functions and constants (``STEPPERS = {"euler":
  euler_step}``), each with the chain that leads to it;
* :func:`blame` takes the records of one notebook's tests, each naming the function it judges
  (``TestRecord.function``), and rewrites the reason of a failed test of B that uses a helper A whose own
  tests failed too: "`B` calls `A`, which fails its own tests: fix `A` first; <the reason>". Of several
  such helpers the most upstream is named (one that uses no other failing helper). A failed test of a
  parametrized function (``test_x[midpoint]``) counts only for the tests that share a parameter with it
  or have none, so that ``measured_order('euler')`` is not blamed on a wrong ``midpoint_step``. A
  failure that no tested helper explains ends with the student's helpers of B that no test judges (and
  that B does not reach only through a tested helper whose tests pass): "(`max_stable_step` relies on `stable_limit`, `bisect_stable` of
  yours, which no test checks alone: the mistake may be there)". And a failure of a function that adds into
  an array at an index array (``dx[i] += c``: NumPy keeps one addition per repeated index) says so, and
  that np.add.at or np.bincount keep them all (:func:`scatter_hazards`).
"""

import ast

__all__ = ["helpers", "blame", "function_of", "params_of", "scatter_hazards", "stub_functions"]


def _is_function(code, name):
    s = code._definition(name)
    return s is not None and isinstance(s.node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)) or (
        s is not None and isinstance(s.node, (ast.Assign, ast.AnnAssign)) and isinstance(s.node.value, ast.Lambda))


def helpers(code, name):
    """The notebook's functions that function `name` uses, directly or through other names of the notebook.

    Parameters
    ----------
    code : particles.course.reading.submission.SubmissionCode
    name : str
        A top-level function of the submission.

    Returns
    -------
    dict
        helper name -> the chain of names from `name` to it (``["measured_order", "convergence_errors",
        "STEPPERS", "rk4_step"]``), in the order found (nearest first); `name` itself is not in it.
    """
    cache = code._cache.setdefault("helpers", {})
    if name in cache:
        return dict(cache[name])
    found, seen, queue = {}, {name}, [(name, [name])]
    while queue:
        current, chain = queue.pop(0)
        for s in code._in_force(current):
            for ref in s.refs:
                if ref.imported is not None or ref.name in seen:
                    continue
                if not code._in_force(ref.name):
                    continue  # a builtin, a parameter of nothing, a library name
                seen.add(ref.name)
                path = chain + [ref.name]
                if _is_function(code, ref.name):
                    found[ref.name] = path
                if all(p.kind != "import" for p in code._in_force(ref.name)):
                    queue.append((ref.name, path))
    cache[name] = found
    return dict(found)


def params_of(test):
    """The parameters of a test key: ``"test_x[a-b]"`` -> ``{"a", "b"}``, ``"test_x"`` -> ``set()``."""
    if test.endswith("]") and "[" in test:
        return set(test[test.index("[") + 1:-1].split("-"))
    return set()


def function_of(test, called, defined):
    """The function a test judges: of those it called, the longest whose name is in the test's name, else the first.

    Parameters
    ----------
    test : str
        The test's key (``test_measured_order_circle[rk4]``).
    called : list of str
        The submission's functions the test called, in order.
    defined : container of str
        The submission's top-level names.
    """
    base = test.split("[", 1)[0]
    named = [name for name in dict.fromkeys(called) if name in base]
    if named:
        return max(named, key=len)
    return next((name for name in called if name in defined), "")


def _own_fault(r):
    """Whether the reason is about the function itself: not written yet, or not defined (nothing to blame)."""
    return r.reason.startswith((f"`{r.function}` is not implemented yet", f"`{r.function}` is not defined"))


def _relevant(test, other):
    a, b = params_of(test), params_of(other)
    return not a or not b or bool(a & b)


def stub_functions(path):
    """The functions a released stub leaves to write (their body raises NotImplementedError), or None without one.

    These are the student's own functions; the others the course provides (``chain_field``), which the
    grader never names as suspects.
    """
    from ..reading.submission import notebook_cells

    try:
        cells = notebook_cells(path)
    except (OSError, ValueError):
        return None
    names = set()
    for _, source in cells:
        try:
            tree = ast.parse(source)
        except SyntaxError:
            continue
        for node in tree.body:
            if isinstance(node, ast.FunctionDef) and any(
                    isinstance(n, ast.Raise) and "NotImplementedError" in ast.unparse(n) for n in ast.walk(node)):
                names.add(node.name)
    return names


def blame(records, code, written=None):
    """Prefix the reasons of failed tests whose function uses a helper that fails its own tests (in place).

    Parameters
    ----------
    records : list of particles.course.results.records.TestRecord
        One notebook's tests, each with ``function`` set where known.
    code : particles.course.reading.submission.SubmissionCode
    written : set of str, optional
        The functions the student writes (:func:`stub_functions`); only those are named as suspects.

    Returns
    -------
    int
        How many reasons were rewritten.
    """
    failed = {}  # function -> its failed tests (not the grader's own errors)
    for r in records:
        if not r.passed and not r.grader_error and r.function:
            failed.setdefault(r.function, []).append(r.test)
    changed = 0
    for r in records:
        if r.passed or r.grader_error or not r.function or r.reason.startswith(f"`{r.function}` calls `") \
                or _own_fault(r):
            continue
        uses = helpers(code, r.function)
        culprits = [a for a in uses if a != r.function and any(_relevant(r.test, t) for t in failed.get(a, []))]
        if not culprits:
            continue
        roots = [a for a in culprits if not any(b in helpers(code, a) for b in culprits if b != a)] or culprits
        a = roots[0]
        through = [n for n in uses[a][1:-1] if _is_function(code, n)]
        via = f" (through `{'`, `'.join(through)}`)" if through else ""
        r.reason = f"`{r.function}` calls `{a}`{via}, which fails its own tests: fix `{a}` first; {r.reason}"
        changed += 1
    changed += _suspects(records, code, written)
    changed += _scatters(records, code)
    return changed


def _loop_names(function):
    """Names bound by the ``for`` loops and comprehensions of a function: scalars, one at a time."""
    names = set()
    for node in ast.walk(function):
        if isinstance(node, (ast.For, ast.comprehension)):
            names |= {n.id for n in ast.walk(node.target) if isinstance(n, ast.Name)}
    return names


def _is_mask(node, masks):
    """Whether an expression is a boolean mask: a comparison, a mask name, or ``~``, ``&``, ``|``, ``^`` of masks."""
    if isinstance(node, ast.Compare):
        return True
    if isinstance(node, ast.Name):
        return node.id in masks
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.Invert, ast.Not)):
        return _is_mask(node.operand, masks)
    if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.BitAnd, ast.BitOr, ast.BitXor)):
        return _is_mask(node.left, masks) and _is_mask(node.right, masks)
    return False


def _mask_names(function):
    """Names a function binds once, to a boolean mask (``inside = H < 0``): an index of them never repeats."""
    assigned, masks = {}, set()
    for node in ast.walk(function):
        if isinstance(node, ast.Assign):
            for target in node.targets:
                if isinstance(target, ast.Name):
                    assigned.setdefault(target.id, []).append(node.value)
    for _ in range(3):  # masks made of masks, a few levels deep
        masks = {name for name, values in assigned.items() if all(_is_mask(v, masks) for v in values)}
    return masks


def _array_index(index, loops):
    """Whether a subscript's index may be an array of indices: a name no loop binds, or an expression of one.

    `loops` holds the names that are safe: scalars a loop binds, and boolean masks (``x[inside] -= ...``
    changes each selected row once).
    """
    if isinstance(index, ast.Tuple):
        return any(_array_index(e, loops) for e in index.elts)
    if isinstance(index, (ast.Slice, ast.Constant)) or _is_mask(index, loops):
        return False
    names = [n.id for n in ast.walk(index) if isinstance(n, ast.Name)]
    return bool(names) and not all(n in loops for n in names)


def scatter_hazards(code, name):
    """``x[i] += ...`` statements of function `name` whose index may hold repeated indices, as (label, line, text).

    NumPy's ``x[i] += c`` reads ``x[i]`` once and writes it once: where ``i`` repeats, only one of the additions
    is kept (``np.add.at(x, i, c)`` or ``np.bincount`` keep them all). An index a ``for`` loop binds is a
    scalar and safe, and a statement inside a loop is left alone (a loop over colours, Gauss-Seidel: sets
    of indices that share no particle, on purpose). So is a boolean mask (``x[inside] -= H[inside] * n``).
    """
    s = code._definition(name)
    if s is None or not isinstance(s.node, (ast.FunctionDef, ast.AsyncFunctionDef)):
        return []
    loops, found = _loop_names(s.node) | _mask_names(s.node), []
    in_loops = {id(n) for loop in ast.walk(s.node) if isinstance(loop, (ast.For, ast.While))
                for stmt in loop.body for n in ast.walk(stmt)}
    for node in ast.walk(s.node):
        if isinstance(node, ast.AugAssign) and isinstance(node.op, (ast.Add, ast.Sub)) and id(node) not in in_loops \
                and isinstance(node.target, ast.Subscript) and _array_index(node.target.slice, loops):
            found.append((s.label, node.lineno, ast.unparse(node.target)))
    return found


def _scatters(records, code):
    """End the reasons of failed tests whose function scatters with ``x[i] +=`` at an index array."""
    changed = 0
    for r in records:
        if r.passed or r.grader_error or not r.function or "np.add.at" in r.reason or "repeated ind" in r.reason \
                or _own_fault(r):
            continue
        for function in [r.function]:  # its own code only: a helper may scatter over disjoint indices on purpose
            hazards = scatter_hazards(code, function)
            if hazards:
                label, line, target = hazards[0]
                r.reason += (f"; `{function}` adds into `{target}` with += ({label}, line {line}): where the index "
                             "repeats, NumPy keeps only one of the additions (lost updates at shared particles); "
                             "scatter with np.add.at or np.bincount")
                changed += 1
                break
    return changed


def _suspects(records, code, written=None):
    """End the reasons of failed tests, not blamed on a tested helper, with the untested helpers they rely on.

    A helper no test judges (``bisect_stable`` under ``max_stable_step``) is a suspect of a failure of a
    function that uses it, unless it is reached only through a tested helper of that function whose tests
    all pass (``grows`` under ``blows_up``). Only the student's functions (`written`, when known) are named.
    """
    judged = {}
    for r in records:
        if r.function:
            judged.setdefault(r.function, []).append(r.passed or r.grader_error)
    changed = 0
    for r in records:
        if r.passed or r.grader_error or not r.function or "which fails its own tests" in r.reason \
                or "which no test checks alone" in r.reason or _own_fault(r):
            continue
        uses = helpers(code, r.function)
        cleared = set()
        for p in uses:
            if p in judged and all(judged[p]):
                cleared |= set(helpers(code, p))
        suspects = [a for a in uses if a not in judged and a not in cleared and a != r.function
                    and (written is None or a in written)]
        if suspects:
            names = ", ".join(f"`{a}`" for a in suspects)
            r.reason += (f" (`{r.function}` relies on {names} of yours, which no test checks alone: the mistake may "
                         f"be there)")
            changed += 1
    return changed
