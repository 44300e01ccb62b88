;;;; Lisp names ↔ ROS names (frames, parameters, topics).

(in-package :roslisp-utilities)

(defun name-string (name what)
  "The name of the symbol or string NAME; an error naming NAME and WHAT otherwise."
  (typecase name
    ((and symbol (not null)) (symbol-name name))
    (string (if (plusp (length name)) name (ros-fail "~a: empty name string, expected a name" what)))
    (t (ros-fail "~a: ~s, expected a symbol or a non-empty string" what name))))

(defun rosify-lisp-name (name)
  "NAME (a symbol or string) in ROS's lower case: BOTTLE-1 → \"bottle-1\"."
  (string-downcase (name-string name 'rosify-lisp-name)))

(defun rosify-underscores-lisp-name (name)
  "NAME (a symbol or string) as a ROS name with underscores: BOTTLE-1 → \"bottle_1\",
:IAI-KITCHEN → \"iai_kitchen\"."
  (substitute #\_ #\- (string-downcase (name-string name 'rosify-underscores-lisp-name))))

(defun lispify-ros-name (name &optional (package :keyword))
  "The symbol in PACKAGE named by the ROS name NAME upcased: \"bottle-1\" → :BOTTLE-1."
  (intern (string-upcase (name-string name 'lispify-ros-name)) package))

(defun lispify-ros-underscore-name (name &optional (package :keyword))
  "The symbol in PACKAGE for the ROS name NAME with underscores read as hyphens:
\"iai_kitchen\" → :IAI-KITCHEN."
  (intern (string-upcase (substitute #\- #\_ (name-string name 'lispify-ros-underscore-name)))
          package))
