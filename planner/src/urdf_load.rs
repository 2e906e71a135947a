//! Reading a URDF (urdf-rs) and building its kinematic tree (k), after checking the things k
//! would otherwise panic on or silently drop.

use crate::error::UrdfError;
use std::collections::{BTreeMap, BTreeSet};

/// Parses URDF text and checks that it is a single tree of supported joints.
pub fn parse(text: &str) -> Result<urdf_rs::Robot, UrdfError> {
    if text.contains("xmlns:xacro") || text.contains("<xacro:") {
        return Err(UrdfError::Xacro);
    }
    // urdf-rs's own parse of the same text reports any syntax error.
    if let Ok(root) = text.parse::<xml::Element>() {
        check_attribute_namespaces(&root, &mut BUILT_IN_PREFIXES.to_vec())?;
    }
    let robot = urdf_rs::read_from_string(text).map_err(|e| UrdfError::Xml(e.to_string()))?;
    validate(&robot)?;
    Ok(robot)
}

/// The namespaces RustyXML knows a prefix of before any declaration: `xml` and `xmlns`.
const BUILT_IN_PREFIXES: [&str; 2] = [XMLNS_NAMESPACE, "http://www.w3.org/XML/1998/namespace"];

/// The namespace of the `xmlns:PREFIX` attributes that declare a prefix.
const XMLNS_NAMESPACE: &str = "http://www.w3.org/2000/xmlns/";

/// Checks that every namespaced attribute of `element` and its descendants has a prefix
/// declared for its namespace, `bound` holding those declared around `element`. urdf-rs
/// prints the parsed document back through RustyXML, which panics on one without (an
/// attribute named `:NAME` inside a default namespace gets that namespace and no prefix; found
/// by the `urdf` fuzz target).
fn check_attribute_namespaces<'a>(
    element: &'a xml::Element,
    bound: &mut Vec<&'a str>,
) -> Result<(), UrdfError> {
    let outer = bound.len();
    for ((_, namespace), value) in &element.attributes {
        if namespace.as_deref() == Some(XMLNS_NAMESPACE) {
            bound.push(value);
        }
    }
    for (name, namespace) in element.attributes.keys() {
        if let Some(namespace) = namespace {
            if !bound.contains(&namespace.as_str()) {
                return Err(UrdfError::Xml(format!(
                    "attribute `{name}` of <{}> is in namespace `{namespace}` but has no prefix declared for it",
                    element.name
                )));
            }
        }
    }
    for child in &element.children {
        if let xml::Xml::ElementNode(child) = child {
            check_attribute_namespaces(child, bound)?;
        }
    }
    bound.truncate(outer);
    Ok(())
}

/// The k kinematic tree of a validated URDF.
pub fn chain(robot: &urdf_rs::Robot) -> k::Chain<f64> {
    k::Chain::from(robot)
}

/// Checks that links and joints form one tree, joint types are supported, mimic targets exist
/// and numbers are finite. Every problem found is reported, each naming its joint or link:
/// one alone as itself, several as [`UrdfError::Several`].
pub(crate) fn validate(robot: &urdf_rs::Robot) -> Result<(), UrdfError> {
    let mut problems = Vec::new();
    let links: BTreeSet<&str> = robot.links.iter().map(|l| l.name.as_str()).collect();
    if links.len() != robot.links.len() {
        problems.push(UrdfError::DuplicateName("links"));
    }
    let joints: BTreeSet<&str> = robot.joints.iter().map(|j| j.name.as_str()).collect();
    if joints.len() != robot.joints.len() {
        problems.push(UrdfError::DuplicateName("joints"));
    }
    let mut parent_of: BTreeMap<&str, &str> = BTreeMap::new();
    for j in &robot.joints {
        let mut at = |problem: String| {
            problems.push(UrdfError::Joint {
                joint: j.name.clone(),
                problem,
            })
        };
        for link in [&j.parent.link, &j.child.link] {
            if !links.contains(link.as_str()) {
                at(format!("unknown link `{link}`"));
            }
        }
        if parent_of.insert(&j.child.link, &j.parent.link).is_some() {
            at(format!(
                "link `{}` is the child of more than one joint",
                j.child.link
            ));
        }
        match &j.joint_type {
            urdf_rs::JointType::Revolute
            | urdf_rs::JointType::Continuous
            | urdf_rs::JointType::Prismatic
            | urdf_rs::JointType::Fixed => {}
            other => at(format!("joint type {other:?} is not supported")),
        }
        let numbers = j.origin.xyz.iter().chain(j.origin.rpy.iter());
        if numbers.chain(j.axis.xyz.iter()).any(|v| !v.is_finite()) {
            at("origin or axis holds a non-finite number".into());
        }
        // A fixed joint's axis means nothing (ROS tools accept `<axis xyz="0 0 0"/>` there).
        let axis = j.axis.xyz;
        let moves = !matches!(j.joint_type, urdf_rs::JointType::Fixed);
        if moves && axis.iter().map(|v| v * v).sum::<f64>() < 1e-12 {
            at("axis has zero length".into());
        }
        if matches!(
            j.joint_type,
            urdf_rs::JointType::Revolute | urdf_rs::JointType::Prismatic
        ) && !(j.limit.lower.is_finite()
            && j.limit.upper.is_finite()
            && j.limit.lower <= j.limit.upper)
        {
            at(format!(
                "limits [{}, {}] are not finite and ordered",
                j.limit.lower, j.limit.upper
            ));
        }
        if let Some(m) = &j.mimic {
            if !joints.contains(m.joint.as_str()) {
                at(format!("mimics unknown joint `{}`", m.joint));
            }
            let factors = [m.multiplier, m.offset];
            if factors.iter().flatten().any(|v| !v.is_finite()) {
                at("mimic multiplier or offset is not finite".into());
            }
        }
    }
    let roots: Vec<&str> = links
        .iter()
        .copied()
        .filter(|l| !parent_of.contains_key(l))
        .collect();
    if roots.len() != 1 {
        problems.push(UrdfError::NotOneTree(
            roots.iter().map(|r| r.to_string()).collect(),
        ));
    }
    // Every link reaches the root without revisiting a link (no cycles); a cycle is named
    // once, by its first link in name order.
    let mut in_cycle = BTreeSet::new();
    for start in &links {
        let mut seen = BTreeSet::new();
        let mut link = *start;
        while let Some(parent) = parent_of.get(link) {
            if !seen.insert(link) {
                if seen.iter().all(|l| !in_cycle.contains(l)) {
                    problems.push(UrdfError::Cycle(link.to_string()));
                }
                in_cycle.extend(seen);
                break;
            }
            link = parent;
        }
    }
    match problems.len() {
        0 => Ok(()),
        1 => Err(problems.remove(0)),
        _ => Err(UrdfError::Several(problems)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TWO_LINKS: &str = r#"<robot name="r">
        <link name="a"/><link name="b"/>
        <joint name="j" type="revolute"><parent link="a"/><child link="b"/>
          <axis xyz="0 0 1"/><limit lower="-1" upper="1" velocity="1" effort="1"/></joint>
        </robot>"#;

    #[test]
    fn a_simple_tree_parses() {
        let robot = parse(TWO_LINKS).unwrap();
        assert_eq!(chain(&robot).dof(), 1);
    }

    #[test]
    fn unknown_links_and_mimics_are_named() {
        let e = parse(&TWO_LINKS.replace(r#"<child link="b"/>"#, r#"<child link="c"/>"#))
            .unwrap_err()
            .to_string();
        assert!(e.contains("unknown link `c`"), "{e}");
        let e = parse(&TWO_LINKS.replace(
            "<axis",
            r#"<mimic joint="nope" multiplier="1" offset="0"/><axis"#,
        ))
        .unwrap_err()
        .to_string();
        assert!(e.contains("mimics unknown joint `nope`"), "{e}");
    }

    #[test]
    fn xacro_is_named_and_a_fixed_joint_may_have_no_axis() {
        let xacro = r#"<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro">
            <xacro:include filename="arm.xacro"/></robot>"#;
        assert_eq!(parse(xacro).unwrap_err(), UrdfError::Xacro);
        let e = UrdfError::Xacro.to_string();
        assert!(e.contains("xacro file") && e.contains("expand it"), "{e}");
        let fixed = TWO_LINKS
            .replace("revolute", "fixed")
            .replace(r#"<axis xyz="0 0 1"/>"#, r#"<axis xyz="0 0 0"/>"#);
        assert!(parse(&fixed).is_ok());
        let e = parse(&TWO_LINKS.replace(r#"<axis xyz="0 0 1"/>"#, r#"<axis xyz="0 0 0"/>"#))
            .unwrap_err()
            .to_string();
        assert!(e.contains("axis has zero length"), "{e}");
    }

    #[test]
    fn every_problem_is_listed_at_once() {
        let text = TWO_LINKS
            .replace(r#"<child link="b"/>"#, r#"<child link="c"/>"#)
            .replace(r#"<axis xyz="0 0 1"/>"#, r#"<axis xyz="0 0 0"/>"#)
            .replace(
                "</robot>",
                r#"<joint name="k" type="planar"><parent link="a"/>
                <child link="b"/><axis xyz="1 0 0"/></joint></robot>"#,
            );
        let e = parse(&text).unwrap_err();
        let UrdfError::Several(problems) = &e else {
            panic!("{e}")
        };
        assert_eq!(problems.len(), 3, "{e}");
        let e = e.to_string();
        assert!(
            e.contains("3 problems")
                && e.contains("joint `j`: unknown link `c`")
                && e.contains("joint `j`: axis has zero length")
                && e.contains("joint `k`: joint type Planar is not supported"),
            "{e}"
        );
    }

    #[test]
    fn floating_joints_and_forests_are_rejected() {
        let e = parse(&TWO_LINKS.replace("revolute", "floating"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("not supported"), "{e}");
        let e =
            parse(&TWO_LINKS.replace(r#"<link name="b"/>"#, r#"<link name="b"/><link name="c"/>"#))
                .unwrap_err()
                .to_string();
        assert!(e.contains("one root"), "{e}");
    }

    #[test]
    fn an_attribute_in_a_namespace_without_a_prefix_is_refused_not_a_panic() {
        // `:` is read as an attribute with an empty prefix, which RustyXML puts in the default
        // namespace with no prefix to print it by (the `urdf` fuzz target's find).
        let e = parse(r#"<l xmlns=">":=""/>"#).unwrap_err().to_string();
        assert!(e.contains("no prefix declared"), "{e}");
        let e = parse(&TWO_LINKS.replace(
            r#"<robot name="r">"#,
            r#"<robot name="r" xmlns="u" :k="1">"#,
        ))
        .unwrap_err()
        .to_string();
        assert!(e.contains("attribute `k` of <robot>"), "{e}");
        // Declared prefixes, on the element or around it, are fine.
        let declared = TWO_LINKS
            .replace(
                r#"<robot name="r">"#,
                r#"<robot name="r" xmlns:x="u" x:k="1">"#,
            )
            .replace(
                r#"<link name="a"/>"#,
                r#"<link name="a" x:k="2" xmlns:y="v" y:k="3"/>"#,
            );
        assert_eq!(chain(&parse(&declared).unwrap()).dof(), 1);
    }
}
