"""``particles warm``: the numba kernels compiled into their disk cache ahead of use."""


def run(args):
    from ..warm import command

    return command(args.jobs)


def register(commands):
    warm = commands.add_parser("warm", help="compile the numba kernels into their disk cache, ahead of use")
    warm.add_argument("--jobs", type=int, default=1, help="processes sharing the work (default 1)")
    warm.set_defaults(run=run)
