;;;; Built-in predicates written as clauses.

(in-package :cram-prolog)

(def-fact-group prolog-library ()
  (<- (append () ?list ?list))
  (<- (append (?head . ?tail) ?list (?head . ?rest))
    (append ?tail ?list ?rest)))

(with-database-lock ()
  (dolist (name '(append))
    (setf (gethash (symbol-name name) *builtin-names*) (ensure-pred name))))
