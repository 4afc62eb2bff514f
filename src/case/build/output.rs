//! The output: how many rows, and the columns, each a probe of the scene, the family's
//! contract columns first.

use super::{Builder, err, identifier};
use crate::case::file::{CaseFile, ColumnTable};
use crate::contract;
use crate::scene::*;
use nalgebra::Vector3;

/// The case's output columns, in file order: at least the contract's rows, names unique and
/// none an engine adds, the family's contract columns first and in order.
pub(super) fn columns(
    b: &Builder,
    case: &CaseFile,
    family: Family,
    contacts: &[ContactPair],
) -> Result<Vec<Column>, SceneError> {
    if case.output.rows < contract::MIN_ROWS {
        return err(
            "output.rows",
            format!("is {}; the contract needs at least 200", case.output.rows),
        );
    }
    let mut columns = Vec::new();
    for (i, c) in case.output.columns.iter().enumerate() {
        let field = format!("output.columns[{i}]");
        let probe = probe(b, &field, c, contacts)?;
        column_name(&field, c, &columns)?;
        columns.push(Column {
            name: c.name.clone(),
            probe,
        });
    }
    let contract = contract::columns(family);
    for (i, name) in contract.iter().enumerate() {
        let got = columns.get(i).map(|c| c.name.as_str());
        if got != Some(*name) {
            return err(
                format!("output.columns[{i}]"),
                format!(
                    "is {}, but column {} of a {} case must be `{name}` (the contract: {})",
                    got.map_or("missing".to_string(), |g| format!("`{g}`")),
                    i + 1,
                    family.name(),
                    contract.join(", ")
                ),
            );
        }
    }
    Ok(columns)
}

/// What a column measures: exactly one of a node's displacement or velocity along a
/// direction, a body's rotation about an axis, a contact's force or gap, or zero.
fn probe(
    b: &Builder,
    field: &str,
    c: &ColumnTable,
    contacts: &[ContactPair],
) -> Result<Probe, SceneError> {
    let set = [
        c.displacement.is_some(),
        c.velocity.is_some(),
        c.rotation.is_some(),
        c.contact_force.is_some(),
        c.gap.is_some(),
        c.zero.is_some(),
    ]
    .iter()
    .filter(|x| **x)
    .count();
    if set != 1 {
        return err(
            field,
            "give exactly one of displacement, velocity, rotation, contact_force, gap, zero",
        );
    }
    let direction = |c: &ColumnTable| -> Result<Vector3<f64>, SceneError> {
        match &c.direction {
            Some(d) => b.unit(&format!("{field}.direction"), d),
            None => err(
                format!("{field}.direction"),
                "this column needs `direction`",
            ),
        }
    };
    Ok(if let Some(n) = &c.displacement {
        Probe::Displacement {
            node: b.node(&format!("{field}.displacement"), n)?,
            direction: direction(c)?,
        }
    } else if let Some(n) = &c.velocity {
        Probe::Velocity {
            node: b.node(&format!("{field}.velocity"), n)?,
            direction: direction(c)?,
        }
    } else if let Some(name) = &c.rotation {
        rotation(b, field, c, name)?
    } else if let Some((key, name)) = c
        .contact_force
        .as_ref()
        .map(|n| ("contact_force", n))
        .or(c.gap.as_ref().map(|n| ("gap", n)))
    {
        let Some(k) = contacts.iter().position(|p| &p.name == name) else {
            return err(
                format!("{field}.{key}"),
                format!("names contact `{name}`, which the case does not define"),
            );
        };
        if key == "gap" {
            Probe::Gap { contact: k }
        } else {
            Probe::ContactForce { contact: k }
        }
    } else {
        Probe::Zero {
            reason: c.zero.clone().unwrap_or_default(),
        }
    })
}

/// A body's rotation about an axis (in 2D, z).
fn rotation(b: &Builder, field: &str, c: &ColumnTable, name: &str) -> Result<Probe, SceneError> {
    let axis = match (&c.axis, b.dim) {
        (None, _) => Vector3::z(),
        (Some(_), Dimension::Two) => {
            return err(
                format!("{field}.axis"),
                "a 2D rotation is about z; drop `axis`",
            );
        }
        (Some(a), Dimension::Three) => b.unit(&format!("{field}.axis"), a)?,
    };
    Ok(Probe::Rotation {
        body: b.body(&format!("{field}.rotation"), name)?,
        axis,
    })
}

/// A column's name: a valid id, none of the columns an engine adds, not already a column.
fn column_name(field: &str, c: &ColumnTable, columns: &[Column]) -> Result<(), SceneError> {
    identifier(&format!("{field}.name"), &c.name)?;
    if c.name == "t"
        || contract::ENERGY_COLUMNS.contains(&c.name.as_str())
        || c.name == contract::VALID_COLUMN
    {
        return err(
            format!("{field}.name"),
            format!(
                "`{}` is a column an engine adds (t, {}, {}); choose another name",
                c.name,
                contract::ENERGY_COLUMNS.join(", "),
                contract::VALID_COLUMN
            ),
        );
    }
    if columns.iter().any(|x: &Column| x.name == c.name) {
        return err(
            format!("{field}.name"),
            format!("`{}` is already a column", c.name),
        );
    }
    Ok(())
}
