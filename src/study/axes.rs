//! The points of a study: the varied keys (`--vary KEY=V1,V2,...`), their product or, for the
//! keys given to `--zip`, their pairing, and the `--set` overrides each point runs with. The
//! values stay the text given, so a point's scene is the one a reader can rebuild with `--set`.

use super::StudyError;

/// One varied key and its values, as given.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Axis {
    pub(super) key: String,
    pub(super) values: Vec<String>,
}

/// The varied keys and, for each point of the study, its value of every key (in the order
/// given).
#[derive(Debug, Clone, PartialEq)]
pub struct Design {
    pub(super) axes: Vec<Axis>,
    points: Vec<Vec<String>>,
}

impl Design {
    /// The points of `--vary` arguments (`KEY=V1,V2,...`): their product, or with `zip` (the
    /// keys of `--zip`, all of them when empty) those keys' lists paired. Refuses a malformed
    /// argument, a key given twice and a zip of lists of unequal length.
    pub fn new(vary: &[String], zip: Option<&[String]>) -> Result<Design, StudyError> {
        let axes: Vec<Axis> = vary
            .iter()
            .map(|v| parse_vary(v))
            .collect::<Result<_, _>>()?;
        for (i, a) in axes.iter().enumerate() {
            if axes[..i].iter().any(|b| b.key == a.key) {
                return Err(StudyError::VaryTwice(a.key.clone()));
            }
        }
        let points = points(&axes, zip)?;
        Ok(Design { axes, points })
    }

    /// The varied keys, in the order given.
    pub fn keys(&self) -> Vec<String> {
        self.axes.iter().map(|a| a.key.clone()).collect()
    }

    /// Each point's values, in point order (a point's index is its place here).
    pub fn points(&self) -> &[Vec<String>] {
        &self.points
    }

    /// The overrides of point `index`: the held keys `set`, then its varied values.
    pub fn overrides(&self, set: &[String], index: usize) -> Vec<String> {
        let mut o = set.to_vec();
        o.extend(self.assignments(index));
        o
    }

    /// Point `index` as `key=value, ...`, for messages.
    pub fn describe(&self, index: usize) -> String {
        self.assignments(index).collect::<Vec<_>>().join(", ")
    }

    fn assignments(&self, index: usize) -> impl Iterator<Item = String> + '_ {
        self.axes
            .iter()
            .zip(&self.points[index])
            .map(|(a, v)| format!("{}={v}", a.key))
    }
}

/// `KEY=V1,V2,...`, split at the commas outside brackets and quotes.
fn parse_vary(s: &str) -> Result<Axis, StudyError> {
    let (key, list) = s
        .split_once('=')
        .ok_or_else(|| StudyError::VaryForm(s.to_string()))?;
    let key = key.trim();
    if key.is_empty() {
        return Err(StudyError::VaryEmptyKey(s.to_string()));
    }
    let (mut values, mut depth, mut quoted, mut start) = (Vec::new(), 0i32, false, 0);
    for (i, c) in list.char_indices() {
        match c {
            '"' => quoted = !quoted,
            '[' | '{' if !quoted => depth += 1,
            ']' | '}' if !quoted => depth -= 1,
            ',' if !quoted && depth == 0 => {
                values.push(list[start..i].trim().to_string());
                start = i + 1;
            }
            _ => {}
        }
    }
    values.push(list[start..].trim().to_string());
    if let Some(i) = values.iter().position(String::is_empty) {
        return Err(StudyError::VaryEmptyValue {
            arg: s.to_string(),
            number: i + 1,
        });
    }
    Ok(Axis {
        key: key.to_string(),
        values,
    })
}

/// The points of the study: for each, its value of every axis (in the order given). The
/// axes in `zip` (all of them for an empty list) vary together, as one axis; the product runs
/// over that one and the others.
fn points(axes: &[Axis], zip: Option<&[String]>) -> Result<Vec<Vec<String>>, StudyError> {
    let zipped = |a: &Axis| zip.is_some_and(|z| z.is_empty() || z.contains(&a.key));
    if let Some(key) = zip
        .unwrap_or_default()
        .iter()
        .find(|k| !axes.iter().any(|a| &a.key == *k))
    {
        return Err(StudyError::ZipKey(key.clone()));
    }
    // Each slot is a list of choices; a choice sets some axes (by index) to values.
    let mut slots: Vec<Vec<Vec<(usize, String)>>> = Vec::new();
    let group: Vec<usize> = (0..axes.len()).filter(|&i| zipped(&axes[i])).collect();
    for (i, a) in axes.iter().enumerate() {
        if group.first() == Some(&i) {
            let n = a.values.len();
            if let Some(&j) = group.iter().find(|&&j| axes[j].values.len() != n) {
                return Err(StudyError::ZipLengths {
                    first: a.key.clone(),
                    count: n,
                    other: axes[j].key.clone(),
                    other_count: axes[j].values.len(),
                });
            }
            slots.push(
                (0..n)
                    .map(|k| {
                        group
                            .iter()
                            .map(|&j| (j, axes[j].values[k].clone()))
                            .collect()
                    })
                    .collect(),
            );
        } else if !group.contains(&i) {
            slots.push(a.values.iter().map(|v| vec![(i, v.clone())]).collect());
        }
    }
    let choices = slots.iter().fold(vec![Vec::new()], |acc, slot| {
        acc.iter()
            .flat_map(|p: &Vec<(usize, String)>| {
                slot.iter().map(move |c| {
                    let mut p = p.clone();
                    p.extend(c.iter().cloned());
                    p
                })
            })
            .collect()
    });
    Ok(choices
        .into_iter()
        .map(|mut c| {
            c.sort_by_key(|(i, _)| *i);
            c.into_iter().map(|(_, v)| v).collect()
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vary_lists_split_outside_brackets_and_quotes() {
        let a = parse_vary("grid.resolution=[32,32,1],[64,64,1]").expect("parses");
        assert_eq!(a.values, ["[32,32,1]", "[64,64,1]"]);
        let a = parse_vary("name=\"a,b\",c").expect("parses");
        assert_eq!(a.values, ["\"a,b\"", "c"]);
        assert!(parse_vary("fluid.spacing").is_err());
        assert!(parse_vary("fluid.spacing=0.1,,0.2").is_err());
    }

    #[test]
    fn points_are_the_product_or_the_pairs() {
        let axes = [
            parse_vary("a=1,2").expect("parses"),
            parse_vary("b=x,y,z").expect("parses"),
        ];
        let p = points(&axes, None).expect("product");
        assert_eq!(p.len(), 6);
        assert_eq!(p[0], ["1", "x"]);
        assert_eq!(p[5], ["2", "z"]);
        assert!(points(&axes, Some(&[])).is_err(), "lists of unequal length");
        let zipped = points(&axes[..1], Some(&[])).expect("one axis");
        assert_eq!(zipped, [["1"], ["2"]]);
        // Two keys paired, the product over that pair and a third key.
        let axes = [
            parse_vary("n=32,64").expect("parses"),
            parse_vary("m=x,y").expect("parses"),
            parse_vary("depth=0.2,0.1").expect("parses"),
        ];
        let keys = ["n".to_string(), "depth".to_string()];
        let p = points(&axes, Some(&keys)).expect("group");
        assert_eq!(
            p,
            [
                ["32", "x", "0.2"],
                ["32", "y", "0.2"],
                ["64", "x", "0.1"],
                ["64", "y", "0.1"]
            ]
        );
        assert!(
            points(&axes, Some(&["q".to_string()])).is_err(),
            "not a varied key"
        );
    }
}
