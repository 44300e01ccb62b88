;;;; Tests of CRAM-WALKER and of DEF-PLAN / DEF-TOP-LEVEL-PLAN: plan trees of calls and tags.

(defpackage :cram-walker-tests
  (:use :cl :fiveam))

(in-package :cram-walker-tests)

(def-suite cram-walker :in cram-plans-tests:all
  :description "EXPAND-PLAN, WALK-WITH-TAG-HANDLER, DEF-PLAN.")
(in-suite cram-walker)

(cpl:def-plan walker-plan-a ()
  (:tag fetch (list 1 2 3)))

(cpl:def-plan walker-plan-b (items)
  (dolist (item items) (print item (make-broadcast-stream))))

(cpl:def-plan walker-plan-c (x y)
  (let ((z 1))
    (cpl:par
      (:tag sum (list (+ x y z)
                      (symbol-macrolet ((really-plan-a (walker-plan-a)))
                        (walker-plan-b really-plan-a))))
      (:tag other (list x)))))

(cpl:def-top-level-plan walker-top-plan ()
  (flet ((walker-plan-b (&rest args) args))
    (macrolet ((disguised-c (a b) `(walker-plan-c ,a ,b)))
      (cpl:seq (disguised-c 2 3)
               (walker-plan-b (list :a :b))))))

(defun correct-parents-p (tree)
  (every (lambda (child) (and (eq tree (walker:plan-tree-node-parent child))
                              (correct-parents-p child)))
         (walker:plan-tree-node-children tree)))

(defun shape (node)
  "The tree as nested lists of the first step of each path."
  (cons (car (walker:plan-tree-node-path node))
        (mapcar #'shape (walker:plan-tree-node-children node))))

(test expand-plan-builds-the-tree-of-plans-and-tags
  (let ((tree (walker:expand-plan '(walker-top-plan))))
    (is-true (correct-parents-p tree))
    (is (equal '(nil
                 ((walker-top-plan)
                  ((walker-plan-c)
                   ((walker::tagged sum) ((walker-plan-a) ((walker::tagged fetch)))
                    ((walker-plan-b)))
                   ((walker::tagged other)))))
               (shape tree))
        "the local WALKER-PLAN-B of the top-level plan is no plan call; the one in C is")
    (let ((fetch (walker:find-plan-node
                  tree '((walker::tagged fetch) (walker-plan-a) (walker::tagged sum)
                         (walker-plan-c) (walker-top-plan)))))
      (is (walker:plan-tree-node-p fetch))
      (is (equal '(:tag fetch (list 1 2 3)) (walker:plan-tree-node-sexp fetch))))
    (is (null (walker:find-plan-node tree '((walker::tagged nowhere)))))
    (signals simple-error (walker:find-plan-node tree 42))
    (signals simple-error (walker:find-plan-node 42 '()))))

(test walk-with-tag-handler-reports-tags-in-order
  (flet ((tags (form)
           (let ((seen '()))
             (walker:walk-with-tag-handler form (lambda (name body) (declare (ignore body))
                                                  (push name seen)))
             (nreverse seen))))
    (is (equal '(one two) (tags '(cpl:par (:tag one (list 1)) (:tag two (list 2))))))
    (is (equal '(outer inner) (tags '(:tag outer (let ((x 1)) (:tag inner x))))))
    (is (equal '(shadowed) (tags '(macrolet ((:tag (&rest r) r)) (:tag shadowed 1)))))
    (is (equal '() (tags ''(:tag quoted 1))))
    (signals error (tags '(:tag)))))

(test def-plan-functions-run-their-tags
  (let ((result nil))
    (walker-top-plan)
    (setf result (walker-plan-a))
    (is (equal '(1 2 3) result))
    (is (eq 'walker-top-plan (cpl:node-name cpl:*last-task-tree*)))
    (is (equal '(sum fetch other)
               (mapcar #'cpl:node-name
                       (cpl:find-task-tree-nodes (lambda (n) (eq :tag (cpl:node-kind n)))))))))
