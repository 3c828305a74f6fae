"""Command-line interface (``clearsweep``).

Every :class:`~clearsweep.config.ConfigError`, whichever subcommand raises it,
is reported on stderr as ``clearsweep: error: <message>`` with exit code 2,
and no output file is written. A run whose status is not ``ok`` writes its
results, reports the status on stderr and exits with 1; so does a run whose
output file cannot be written (nothing is left at its path).
"""

from __future__ import annotations

import importlib
from pathlib import Path

import click

from . import __version__
from .config import ConfigError, dump_config, load_config

#: Subcommands defined in other modules, loaded when first asked for.
_EXTERNAL = {
    "sweep": ("clearsweep.sweeps", "sweep_command"),
    "report": ("clearsweep.analysis", "report_command"),
    "plot": ("clearsweep.plotting", "plot_command"),
}


class _Group(click.Group):
    """Group that loads the external subcommands lazily and reports ``ConfigError`` with exit 2."""

    def get_command(self, ctx: click.Context, name: str) -> click.Command | None:
        if name in _EXTERNAL and name not in self.commands:
            module, attr = _EXTERNAL[name]
            try:
                self.add_command(getattr(importlib.import_module(module), attr), name)
            except (ImportError, AttributeError):
                return None
        return super().get_command(ctx, name)

    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted({*self.commands, *(n for n in _EXTERNAL if self.get_command(ctx, n))})

    def invoke(self, ctx: click.Context):
        try:
            return super().invoke(ctx)
        except ConfigError as exc:
            click.echo(f"clearsweep: error: {exc}", err=True)
            ctx.exit(2)


_overrides = click.option(
    "--set", "overrides", multiple=True, metavar="KEY=VALUE",
    help="Override a config value, VALUE in YAML (e.g. joints.B.coating=PTFE, "
         "solver.baumgarte=[50,50]); repeatable.")


@click.group(cls=_Group, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="clearsweep")
def main() -> None:
    """Dynamics and wear of the RSSP mechanism with clearance and coated spherical joints."""


@main.command()
@click.argument("config", type=click.Path(dir_okay=False))
@click.option("-o", "--out", type=click.Path(dir_okay=False),
              help="Output netCDF file [default: <config stem>.nc in the current folder].")
@_overrides
@click.option("-q", "--quiet", is_flag=True, help="Print nothing but errors.")
@click.pass_context
def run(ctx: click.Context, config: str, out: str | None, overrides: tuple[str, ...], quiet: bool) -> None:
    """Simulate one case described by CONFIG (YAML) and write its results."""
    cfg = load_config(config, overrides)
    from .dataset import write_netcdf_atomic
    from .simulation import simulate

    try:
        ds = simulate(cfg)
    except ConfigError as exc:
        if exc.source != "<config>":
            raise
        # A check on the resolved config (the step bound): name the file it came from.
        raise ConfigError(exc.key, exc.value, exc.expected, config, exc.suggestion,
                          exc.got) from None
    path = Path(out) if out else Path(Path(config).stem + ".nc")
    try:
        write_netcdf_atomic(ds, path)
    except OSError as exc:
        click.echo(f"clearsweep: error: cannot write {path}: {exc.strerror or exc}", err=True)
        ctx.exit(1)
    if not quiet:
        from .analysis import run_summary_text

        click.echo(run_summary_text(ds))
        click.echo(f"wrote {path}")
    status = str(ds["status"].values)
    if status != "ok":
        click.echo(f"clearsweep: run stopped: {status} (results so far in {path})", err=True)
        ctx.exit(1)


@main.command()
@click.argument("config", type=click.Path(dir_okay=False))
@_overrides
def validate(config: str, overrides: tuple[str, ...]) -> None:
    """Check CONFIG and print it resolved (every key, defaults filled) as YAML."""
    click.echo(dump_config(load_config(config, overrides)), nl=False)


@main.command()
@click.option("-m", "--materials-file", type=click.Path(dir_okay=False),
              help="User materials YAML that adds or overrides materials.")
def materials(materials_file: str | None) -> None:
    """List the materials, their properties and the source of every value."""
    from .materials import format_materials, load_materials

    click.echo(format_materials(load_materials(materials_file)))


if __name__ == "__main__":
    main(prog_name="clearsweep")
