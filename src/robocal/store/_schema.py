"""The history schema, described once and rendered for the standard library's sqlite3 (DDL text)
or for SQLAlchemy Core (``Table`` objects, any dialect).

Migrations are a list of ``(version, description, tables, extra)``: ``tables`` are created,
``extra`` are portable SQL statements run after them. The database records each applied
version in ``schema_version``; opening a database applies the missing ones in one transaction.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ._validate import CYCLE_KINDS

SCHEMA_VERSION = 3
CYCLE_STATUSES = ("running", "committed", "failed")


@dataclass(frozen=True)
class Col:
    name: str
    type: str  # pk | int | real | text | name (short string) | time (ISO string) | json
    nullable: bool = True
    unique: bool = False
    references: str | None = None  # "table.column"; ON DELETE CASCADE


@dataclass(frozen=True)
class Tab:
    name: str
    columns: tuple
    unique: tuple = ()  # tuples of column names
    checks: tuple = ()  # (name, portable SQL expression)
    indexes: tuple = ()  # (name, (columns...))


def _in(col, values):
    return f"{col} IN ({', '.join(repr(v) for v in values)})"


SCHEMA_VERSION_TABLE = Tab("schema_version", (
    Col("version", "int", nullable=False, unique=True),
    Col("applied_at", "time", nullable=False),
    Col("description", "text"),
))

V1_TABLES = (
    Tab("robots", (
        Col("id", "pk"),
        Col("name", "name", nullable=False, unique=True),
        Col("model", "name"),
        Col("created_at", "time", nullable=False),
        Col("notes", "text"),
    )),
    Tab("cycles", (
        Col("id", "pk"),
        Col("robot_id", "int", nullable=False, references="robots.id"),
        Col("kind", "name", nullable=False),
        Col("status", "name", nullable=False),
        Col("started_at", "time", nullable=False),
        Col("finished_at", "time"),
        Col("notes", "text"),
        Col("meta", "json"),
    ), checks=(("ck_cycles_kind", _in("kind", CYCLE_KINDS)), ("ck_cycles_status", _in("status", CYCLE_STATUSES))),
        indexes=(("ix_cycles_robot_time", ("robot_id", "started_at")),)),
    Tab("measurements", (
        Col("id", "pk"),
        Col("cycle_id", "int", nullable=False, references="cycles.id"),
        Col("seq", "int", nullable=False),
        Col("pose_index", "int", nullable=False),
        Col("target", "name"),
        Col("sensor", "name"),
        Col("joints", "json"),
        Col("joint_units", "json"),
        Col("x", "real", nullable=False),
        Col("y", "real", nullable=False),
        Col("z", "real", nullable=False),
        Col("unit", "name", nullable=False),
    ), unique=(("cycle_id", "seq"),), indexes=(("ix_measurements_cycle", ("cycle_id",)),)),
    Tab("parameters", (
        Col("id", "pk"),
        Col("cycle_id", "int", nullable=False, references="cycles.id"),
        Col("name", "name", nullable=False),
        Col("value", "real"),
        Col("delta", "real", nullable=False),
        Col("std", "real"),
        Col("unit", "name", nullable=False),
    ), unique=(("cycle_id", "name"),), indexes=(("ix_parameters_name", ("name", "cycle_id")),)),
    Tab("metrics", (
        Col("id", "pk"),
        Col("cycle_id", "int", nullable=False, references="cycles.id"),
        Col("name", "name", nullable=False),
        Col("value", "real", nullable=False),
        Col("unit", "name", nullable=False),
    ), unique=(("cycle_id", "name"),), indexes=(("ix_metrics_name", ("name", "cycle_id")),)),
    Tab("corrections", (
        Col("id", "pk"),
        Col("cycle_id", "int", nullable=False, references="cycles.id"),
        Col("program", "name"),
        Col("point_index", "int", nullable=False),
        Col("point_name", "name"),
        Col("joints_before", "json", nullable=False),
        Col("joints_after", "json", nullable=False),
        Col("joint_units", "json", nullable=False),
    ), unique=(("cycle_id", "program", "point_index"),), indexes=(("ix_corrections_cycle", ("cycle_id",)),)),
)


@dataclass(frozen=True)
class Migration:
    version: int
    description: str
    tables: tuple = ()
    extra: tuple = field(default_factory=tuple)


#: Version 2 (issue 25): one unit per quantity and honest names. ``lambda`` is stored in % (was a
#: fraction, unit "1"); the demo's geometric calibration had stored the simulator-truth workspace
#: errors as ``residual_rms_before/after``: they are renamed to what they are.
V2_EXTRA = (
    "UPDATE metrics SET value = value * 100.0, unit = '%' WHERE name = 'lambda' AND unit = '1'",
    "UPDATE metrics SET name = 'workspace_error_nominal_rms' WHERE name = 'residual_rms_before' AND cycle_id IN "
    "(SELECT id FROM cycles WHERE kind = 'geometric_calibration' AND notes LIKE 'robocal demo%')",
    "UPDATE metrics SET name = 'workspace_error_calibrated_rms' WHERE name = 'residual_rms_after' AND cycle_id IN "
    "(SELECT id FROM cycles WHERE kind = 'geometric_calibration' AND notes LIKE 'robocal demo%')",
)

#: Version 3 (issue 32): the ISO 9283 figures of a performance test and the outcome of a quick
#: verification, each child rows of a cycle (kind ``measurement``: a test or a check measures the
#: robot; the child table says which). New tables only, so every older database gains them as is.
V3_TABLES = (
    Tab("iso9283_figures", (
        Col("id", "pk"),
        Col("cycle_id", "int", nullable=False, references="cycles.id"),
        Col("symbol", "name", nullable=False),      # AP, RP, AP_x, AP_a, vAP, AD, RD, dAP, dRP, AT, RT
        Col("pose", "name", nullable=False),        # P1..P5, line, circle; "" for the run's worst value
        Col("value", "real", nullable=False),
        Col("unit", "name", nullable=False),        # mm | rad
        Col("uncertainty", "real"),                 # the instrument's U for this figure, same unit, or NULL
        Col("adequate", "int"),                     # 1 | 0 | NULL (not assessed)
    ), unique=(("cycle_id", "symbol", "pose"),), indexes=(("ix_iso9283_figures_cycle", ("cycle_id",)),)),
    Tab("verifications", (
        Col("id", "pk"),
        Col("cycle_id", "int", nullable=False, unique=True, references="cycles.id"),
        Col("decision", "name", nullable=False),    # ok | recalibrate | mechanical fault suspected
        Col("statistic", "real", nullable=False),
        Col("dof", "int", nullable=False),
        Col("threshold", "real", nullable=False),
        Col("false_alarm_rate", "real", nullable=False),
        Col("n_poses", "int", nullable=False),
        Col("rms_mm", "real"),
        Col("max_mm", "real"),
        Col("suspect", "name"),                     # e.g. "J3 offset", "J2 backlash"
        Col("suspect_value", "real"),
        Col("suspect_unit", "name"),                # rad | mm
        Col("instrument", "text"),
        Col("temperature_c", "real"),
        Col("model", "text"),                       # the calibration verified against
    ), checks=(("ck_verifications_decision",
                _in("decision", ("ok", "recalibrate", "mechanical fault suspected"))),)),
)

MIGRATIONS = (
    Migration(1, "robots, cycles, measurements, parameters, metrics, corrections", V1_TABLES),
    Migration(2, "lambda in %; the demo's workspace errors named as such (not residuals)", (), V2_EXTRA),
    Migration(3, "ISO 9283 figures and verification outcomes", V3_TABLES),
)
assert MIGRATIONS[-1].version == SCHEMA_VERSION

ALL_TABLES = {t.name: t for m in MIGRATIONS for t in m.tables} | {SCHEMA_VERSION_TABLE.name: SCHEMA_VERSION_TABLE}

# -- sqlite3 DDL ---------------------------------------------------------------------------------

_SQLITE_TYPES = {"pk": "INTEGER PRIMARY KEY", "int": "INTEGER", "real": "REAL", "text": "TEXT", "name": "TEXT",
                 "time": "TEXT", "json": "TEXT"}


def sqlite_ddl(tab: Tab) -> list[str]:
    """``CREATE TABLE`` and ``CREATE INDEX`` statements for SQLite."""
    parts = []
    for c in tab.columns:
        s = f"{c.name} {_SQLITE_TYPES[c.type]}"
        if not c.nullable and c.type != "pk":
            s += " NOT NULL"
        if c.unique:
            s += " UNIQUE"
        if c.references:
            t, col = c.references.split(".")
            s += f" REFERENCES {t}({col}) ON DELETE CASCADE"
        parts.append(s)
    parts += [f"UNIQUE ({', '.join(u)})" for u in tab.unique]
    parts += [f"CONSTRAINT {n} CHECK ({expr})" for n, expr in tab.checks]
    out = [f"CREATE TABLE IF NOT EXISTS {tab.name} (\n  " + ",\n  ".join(parts) + "\n)"]
    out += [f"CREATE INDEX IF NOT EXISTS {n} ON {tab.name} ({', '.join(cols)})" for n, cols in tab.indexes]
    return out


# -- SQLAlchemy Core -----------------------------------------------------------------------------

def sqlalchemy_tables(sa, metadata, tabs) -> dict:
    """SQLAlchemy ``Table`` objects for ``tabs`` on ``metadata`` (``sa`` is the imported module)."""
    types = {"int": sa.Integer, "real": lambda: sa.Float(precision=53), "text": sa.Text, "name": lambda: sa.String(255),
             "time": lambda: sa.String(40), "json": sa.Text}
    out = {}
    for tab in tabs:
        if tab.name in metadata.tables:
            out[tab.name] = metadata.tables[tab.name]
            continue
        items = []
        for c in tab.columns:
            if c.type == "pk":
                items.append(sa.Column(c.name, sa.Integer, primary_key=True, autoincrement=True))
                continue
            args = [types[c.type]()]
            if c.references:
                args.append(sa.ForeignKey(c.references, ondelete="CASCADE"))
            items.append(sa.Column(c.name, *args, nullable=c.nullable, unique=c.unique))
        items += [sa.UniqueConstraint(*u) for u in tab.unique]
        items += [sa.CheckConstraint(expr, name=n) for n, expr in tab.checks]
        t = sa.Table(tab.name, metadata, *items)
        for n, cols in tab.indexes:
            sa.Index(n, *[t.c[cn] for cn in cols])
        out[tab.name] = t
    return out
