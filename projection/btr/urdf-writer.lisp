;;;; GENERATE-URDF-STRING: the URDF text of a parsed (and possibly changed) CL-URDF:ROBOT.

(in-package :cl-urdf)

(defun xml-escape (string)
  "STRING with the characters that XML attribute values cannot hold as they are escaped."
  (with-output-to-string (out)
    (loop for c across string
          do (case c
               (#\& (write-string "&amp;" out))
               (#\< (write-string "&lt;" out))
               (#\> (write-string "&gt;" out))
               (#\" (write-string "&quot;" out))
               (t (write-char c out))))))

(defun urdf-numbers (numbers)
  "NUMBERS as URDF writes them: space-separated decimals that read back as the same doubles."
  (format nil "~{~a~^ ~}"
          (mapcar (lambda (n)
                    (let ((*read-default-float-format* 'double-float))
                      (princ-to-string (coerce n 'double-float))))
                  numbers)))

(defun spaces (n)
  (make-string n :initial-element #\Space))

(defun write-origin (origin out indent)
  (destructuring-bind (xyz quaternion) origin
    (format out "~a<origin xyz=\"~a\" rpy=\"~a\"/>~%" (spaces indent)
            (urdf-numbers xyz) (urdf-numbers (quaternion->rpy quaternion)))))

(defun write-geometry (geometry out indent)
  (format out "~a<geometry>~%" (spaces indent))
  (let ((inner (+ indent 2)))
    (destructuring-bind (kind &key size radius length filename scale) geometry
      (ecase kind
        (:box (format out "~a<box size=\"~a\"/>~%" (spaces inner) (urdf-numbers size)))
        (:cylinder (format out "~a<cylinder radius=\"~a\" length=\"~a\"/>~%" (spaces inner)
                           (urdf-numbers (list radius)) (urdf-numbers (list length))))
        (:sphere (format out "~a<sphere radius=\"~a\"/>~%" (spaces inner)
                         (urdf-numbers (list radius))))
        (:mesh (format out "~a<mesh filename=\"~a\" scale=\"~a\"/>~%" (spaces inner)
                       (xml-escape filename) (urdf-numbers scale))))))
  (format out "~a</geometry>~%" (spaces indent)))

(defun write-link (link out)
  (format out "  <link name=\"~a\">~%" (xml-escape (name link)))
  (dolist (v (visual link))
    (format out "    <visual>~%")
    (write-origin (getf v :origin) out 6)
    (write-geometry (getf v :geometry) out 6)
    (when (getf v :color)
      (format out "      <material name=\"\"><color rgba=\"~a\"/></material>~%"
              (urdf-numbers (getf v :color))))
    (format out "    </visual>~%"))
  (dolist (c (collision link))
    (format out "    <collision>~%")
    (write-origin (getf c :origin) out 6)
    (write-geometry (getf c :geometry) out 6)
    (format out "    </collision>~%"))
  (format out "  </link>~%"))

(defun write-joint (joint out)
  (format out "  <joint name=\"~a\" type=\"~(~a~)\">~%" (xml-escape (name joint)) (joint-type joint))
  (format out "    <parent link=\"~a\"/>~%    <child link=\"~a\"/>~%"
          (xml-escape (name (parent joint))) (xml-escape (name (child joint))))
  (write-origin (origin joint) out 4)
  (format out "    <axis xyz=\"~a\"/>~%" (urdf-numbers (axis joint)))
  (let ((limits (limits joint)))
    (when limits
      (format out "    <limit lower=\"~a\" upper=\"~a\" velocity=\"~a\" effort=\"~a\"/>~%"
              (urdf-numbers (list (getf limits :lower))) (urdf-numbers (list (getf limits :upper)))
              (urdf-numbers (list (getf limits :velocity)))
              (urdf-numbers (list (getf limits :effort))))))
  (let ((mimic (mimic joint)))
    (when mimic
      (format out "    <mimic joint=\"~a\" multiplier=\"~a\" offset=\"~a\"/>~%"
              (xml-escape (getf mimic :joint)) (urdf-numbers (list (getf mimic :multiplier)))
              (urdf-numbers (list (getf mimic :offset))))))
  (format out "  </joint>~%"))

(defun generate-urdf-string (robot)
  "The URDF text of ROBOT (a CL-URDF:ROBOT, e.g. from PARSE-URDF): its links with their visual
and collision geometry and its joints, written from the model (so changes made to it are
included); PARSE-URDF of the text gives an equal model. Links and joints come in name order."
  (unless (typep robot 'robot)
    (urdf-fail "GENERATE-URDF-STRING: expected a CL-URDF:ROBOT (from PARSE-URDF), got ~s" robot))
  (with-output-to-string (out)
    (format out "<?xml version=\"1.0\"?>~%<robot name=\"~a\">~%" (xml-escape (name robot)))
    (dolist (link-name (robot-link-names robot))
      (write-link (gethash link-name (links robot)) out))
    (dolist (joint-name (robot-joint-names robot))
      (write-joint (gethash joint-name (joints robot)) out))
    (format out "</robot>~%")))

(setf (documentation 'name 'function) "The name of a URDF robot, link or joint."
      (documentation 'links 'function) "Hash table of a robot's links by name."
      (documentation 'joints 'function) "Hash table of a robot's joints by name."
      (documentation 'root-link 'function) "The link of a robot that has no parent joint."
      (documentation 'source 'function) "The URDF text a robot was parsed from."
      (documentation 'collision 'function) "A link's collision shapes: plists (:origin :geometry)."
      (documentation 'visual 'function) "A link's visual shapes: plists (:origin :geometry :color)."
      (documentation 'parent-joint 'function) "The joint whose child a link is, or NIL."
      (documentation 'child-joints 'function) "The joints whose parent a link is."
      (documentation 'joint-type 'function) "A joint's type keyword (:revolute, :prismatic ...)."
      (documentation 'parent 'function) "The parent link of a joint."
      (documentation 'child 'function) "The child link of a joint."
      (documentation 'origin 'function) "A joint's origin ((x y z) (qx qy qz qw)) in its parent link."
      (documentation 'axis 'function) "A joint's unit axis (x y z)."
      (documentation 'limits 'function) "A joint's limits plist (:lower :upper :velocity :effort), or NIL."
      (documentation 'mimic 'function) "A joint's mimic plist (:joint :multiplier :offset), or NIL.")
